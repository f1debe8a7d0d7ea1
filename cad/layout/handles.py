"""The handles: one handle design (an octagonal grip on two posts with screw feet) on top of the lid
and, when the rig asks for them, on both sides of it, each standing on printed pads that hold its
feet's inserts. Rig frame, mm."""
from __future__ import annotations

from dataclasses import dataclass

from platform_tools.rig import Rig
from platform_tools.rig.frames import Pose

from cad.geom import Bounds, placed_bounds, pose_xyz

from .case import Shell
from .constants import PAD_MARGIN_MM, Constants
from .fits import Fits

#: a pad reaches this fraction of the wall into the wall it stands on (so the two fuse)
PAD_INTO_WALL = 0.5


@dataclass(frozen=True)
class HandleGeometry:
    """The handle in its own frame (origin on the pad's top face between the feet, x along the grip)."""
    grip_d: float
    grip_length: float
    post_height: float     # from the pad's top face to the grip
    post_width: float
    foot: float
    flange: float

    def foot_screw_x(self) -> list[float]:
        """x of the foot screws in the handle frame, two per foot."""
        px = self.grip_length / 2 - self.post_width / 2
        off = self.post_width / 2 + self.flange / 2
        return [s * px + d * off for s in (-1, 1) for d in (-1, 1)]

    def foot_bounds(self) -> list[Bounds]:
        px = self.grip_length / 2 - self.post_width / 2
        half = self.post_width / 2 + self.flange
        return [Bounds((s * px - half, -self.grip_d / 2, 0.0), (s * px + half, self.grip_d / 2, self.foot))
                for s in (-1, 1)]


@dataclass(frozen=True)
class Handles:
    geometry: HandleGeometry
    pad_mm: float                   # pad thickness: an insert's hole
    poses: dict[str, Pose]          # "top", "left", "right": the handle frame in the rig
    pads: tuple[Bounds, ...]        # one per foot, rig frame


def handle_geometry(rig: Rig, c: Constants, fits: Fits) -> HandleGeometry:
    h = rig.desc.enclosure.handles
    return HandleGeometry(h.grip_diameter_mm, h.grip_length_mm, h.clearance_mm - fits.insert.hole_depth_mm,
                          c.handle_post_width_mm, c.handle_foot_mm, c.handle_flange_mm)


def place_handles(rig: Rig, c: Constants, fits: Fits, shell: Shell) -> Handles:
    """The top handle centred on the lid; the side handles centred on the lid's side walls."""
    h = rig.desc.enclosure.handles
    o, pad_mm = shell.outer, fits.insert.hole_depth_mm
    x_mid = (o.lo[0] + o.hi[0]) / 2
    lid_mid = (shell.split_z + o.hi[2]) / 2
    poses = {}
    if h.top:
        poses["top"] = pose_xyz(x_mid, 0.0, o.hi[2] + pad_mm)
    if h.sides:
        poses["left"] = Pose.from_xyz_rpy_deg((x_mid, o.hi[1] + pad_mm, lid_mid), (-90.0, 0, 0))
        poses["right"] = Pose.from_xyz_rpy_deg((x_mid, o.lo[1] - pad_mm, lid_mid), (90.0, 0, 0))
    g = handle_geometry(rig, c, fits)
    m = PAD_MARGIN_MM
    pads = tuple(placed_bounds(Bounds((fb.lo[0] - m, fb.lo[1] - m, -pad_mm - PAD_INTO_WALL * fits.wall),
                                      (fb.hi[0] + m, fb.hi[1] + m, 0.0)), pose)
                 for pose in poses.values() for fb in g.foot_bounds())
    return Handles(geometry=g, pad_mm=pad_mm, poses=poses, pads=pads)
