"""What printed-part builders share: cutting a list of joint holes, the print orientation type."""
from __future__ import annotations

from dataclasses import dataclass

import cadquery as cq
import numpy as np

from platform_tools.rig.frames import Pose

from ..layout import Hole
from ..solids import cylinder


def hole_tools(holes: tuple[Hole, ...], pose_in_part: Pose | None = None) -> list[cq.Shape]:
    """Cylinders for ``holes`` (given in the rig frame), in the part's frame."""
    tools = []
    inv = pose_in_part.inverse() if pose_in_part is not None else None
    for h in holes:
        o = np.asarray(h.origin, dtype=float)
        d = np.asarray(h.direction, dtype=float)
        if inv is not None:
            o, d = inv.apply(o), inv.rotate(d)
        tools.append(cylinder(h.diameter, h.depth, tuple(o), tuple(d)))
    return tools


@dataclass(frozen=True)
class PrintSetup:
    """How a printed part goes on the bed: a rotation of the part's frame (the translation that puts it
    on the bed's centre is computed from its bounding box)."""
    rpy_deg: tuple[float, float, float]
    why: str


def on_bed(shape: cq.Shape, setup: PrintSetup, bed_mm: tuple[float, float, float]) -> tuple[cq.Shape, Pose]:
    """The part in its print orientation, resting on z = 0 and centred on the bed; and that pose."""
    from ..solids import moved
    rot = Pose.from_xyz_rpy_deg((0, 0, 0), setup.rpy_deg)
    s = moved(shape, rot)
    bb = s.BoundingBox()
    # OCC's box is up to ~0.01 mm loose on a part turned off its axes: rest the part on its lowest mesh point
    zmin = min(v.z for v in s.tessellate(0.01, 0.1)[0])
    shift = np.array([bed_mm[0] / 2 - (bb.xmin + bb.xmax) / 2, bed_mm[1] / 2 - (bb.ymin + bb.ymax) / 2, -zmin])
    pose = Pose(rot.R, shift)
    return moved(shape, pose), pose
