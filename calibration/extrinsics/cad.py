"""The CAD extrinsics: every camera optical frame and the IMU in the rig frame, read from the CAD
assembly's placements (:func:`cad.assembly.camera_frames`), so the STEP and the extrinsics come from
one code path: move a camera in the rig description and both follow.

Frames (platform_tools/rig/frames.py): the rig frame is REP-103 (x forward, y left, z up, mm, origin
at the ZED X centre); optical frames are x right, y down, z forward; ``T_a_b`` maps b into a.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from platform_tools.rig.frames import T_BODY_OPTICAL, Pose
from platform_tools.rig import Rig

#: the four cameras of the rig: short name (folder names, reports) -> optical frame
CAMERAS = {"zed_left": "zed_x_left_optical", "zed_right": "zed_x_right_optical",
           "thermal_left": "thermal_left_optical", "thermal_right": "thermal_right_optical"}
#: the ROS topic key (rig on_device.topics) of each camera
TOPIC_KEYS = {"zed_left": "zed_left", "zed_right": "zed_right", "thermal_left": "thermal_left",
              "thermal_right": "thermal_right"}
IMU = "zed_x_imu"


class RigGeometryError(Exception):
    """The rig description places cameras where they cannot be (one line per problem)."""

    def __init__(self, problems: list[str]):
        self.problems = problems
        super().__init__("; ".join(problems))


@dataclass(frozen=True)
class FrameTree:
    """Named frames in the rig frame (``T_rig``) with their parent, as a URDF tree."""
    T_rig: dict[str, Pose]           # frame name -> pose in the rig frame (mm)
    parent: dict[str, str]           # frame name -> parent frame name ("rig" for the root's children)
    rig_hash: str

    def T(self, a: str, b: str) -> Pose:
        """Pose of frame b in frame a (maps b into a); 'rig' names the rig frame."""
        Ta = Pose.identity() if a == "rig" else self.T_rig[a]
        Tb = Pose.identity() if b == "rig" else self.T_rig[b]
        return Ta.inverse() @ Tb

    def camera(self, short: str) -> Pose:
        return self.T_rig[CAMERAS[short]]


def camera_boxes(rig: Rig) -> dict[str, object]:
    """The body of each camera (ZED X; each Boson core with its lens) as a box in the rig frame."""
    from cad.geom import placed_bounds
    from cad.bought.boson import BosonCore, BosonLens
    from cad.bought.zed_x import ZedX
    s = rig.desc.sensors
    frames = rig.sensor_frames()
    zed = ZedX.from_rig(rig, s.zed_x.part)
    core = BosonCore.from_rig(rig, s.thermal.part, s.thermal.lens)
    lens = BosonLens.from_rig(rig, s.thermal.lens)
    boxes = {"zed_x": placed_bounds(zed.bounds(), frames["zed_x"].T_rig)}
    for side in ("left", "right"):
        pose = frames[f"thermal_{side}"].T_rig
        a, b = placed_bounds(core.bounds(), pose), placed_bounds(lens.bounds(), pose)
        boxes[f"boson_{side}"] = type(a)(tuple(np.minimum(a.lo, b.lo)), tuple(np.maximum(a.hi, b.hi)))
    return boxes


def overlap_problems(rig: Rig) -> list[str]:
    """Cameras whose bodies overlap (boxes in the rig frame), each as one line naming the rig keys."""
    boxes = camera_boxes(rig)
    names = list(boxes)
    out = []
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            A, B = boxes[a], boxes[b]
            depth = np.minimum(np.array(A.hi), np.array(B.hi)) - np.maximum(np.array(A.lo), np.array(B.lo))
            if np.all(depth > 1e-6):
                key = "sensors.thermal.baseline_mm" if {a, b} == {"boson_left", "boson_right"} else \
                    "sensors.thermal.pose.xyz_mm / sensors.zed_x.pose.xyz_mm"
                out.append(f"{key}: the cameras {a} and {b} overlap by {depth.min():.1f} mm "
                           f"(their bodies occupy the same space); move them apart")
    return out


def cad_frames(rig: Rig) -> FrameTree:
    """Every sensor frame as the CAD assembly places it. Raises :class:`RigGeometryError` when cameras
    overlap or the design cannot be made (the CAD model's own checks, naming the rig key)."""
    problems = overlap_problems(rig)
    if problems:
        raise RigGeometryError(problems)
    from cad.assembly import build, camera_frames
    from cad.layout import DesignError
    try:
        asm = build(rig)      # places every part; no geometry is built until a shape is asked for
    except DesignError as exc:
        raise RigGeometryError([str(p) for p in exc.problems]) from None
    optical = camera_frames(asm)
    T: dict[str, Pose] = {}
    T["zed_x"] = asm.node("zed_x").pose
    for side in ("left", "right"):
        T[f"zed_x_{side}_optical"] = optical[f"zed_x_{side}_optical"]
        T[f"zed_x_{side}"] = optical[f"zed_x_{side}_optical"] @ T_BODY_OPTICAL.inverse()
        T[f"thermal_{side}"] = asm.node(f"boson_{side}").pose
        T[f"thermal_{side}_optical"] = optical[f"thermal_{side}_optical"]
    # the IMU has no part of its own: it is inside the ZED X, at the rig's IMU offset from its centre
    T[IMU] = T["zed_x"] @ rig.T("zed_x", IMU)
    rig_frames = rig.sensor_frames()
    ordered = {name: T[name] for name in rig_frames if name in T}
    parent = {name: rig_frames[name].parent for name in ordered}
    return FrameTree(ordered, parent, rig.hash)
