"""Stereolabs ZED X: the RGB stereo camera with its IMU.

Frame: origin at the camera centre (midway between the two optical centres), x forward (the
cameras look along +x), y left, z up, as ``sensors.zed_x.pose`` places it. The body's front face
is ``optical_centre_behind_front_mm`` ahead of the optical centres. Mounting: the bottom 1/4-20
thread(s) of ``parts.zed_x.mounting``, positions from the bottom face's centre.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from platform_tools.rig.frames import T_BODY_OPTICAL, Pose
from platform_tools.rig import Rig

from cad.geom import Bounds
from cad.bought.base import BoughtPart, envelope, part_colour

if TYPE_CHECKING:
    import cadquery as cq


@dataclass(frozen=True)
class ZedX(BoughtPart):
    baseline_mm: float = 0.0
    front_mm: float = 0.0                 # front face, ahead of the optical centres
    lens_window_mm: float = 0.0
    mount_thread: str = ""
    mount_uv_mm: tuple[tuple[float, float], ...] = ()
    mount_depth_mm: float = 0.0

    @classmethod
    def from_rig(cls, rig: Rig, part_id: str) -> "ZedX":
        m = next(m for m in rig.part(part_id).mounting if m.face.value == "bottom")
        return cls(part_id, envelope(rig, part_id), part_colour("camera"),
                   baseline_mm=rig.dim(part_id, "baseline_mm"),
                   front_mm=rig.dim(part_id, "optical_centre_behind_front_mm"),
                   lens_window_mm=rig.dim(part_id, "lens_window_diameter_mm"),
                   mount_thread=m.thread, mount_uv_mm=m.positions_mm, mount_depth_mm=m.depth_mm)

    def bounds(self) -> Bounds:
        x, y, z = self.size
        return Bounds((self.front_mm - x, -y / 2, -z / 2), (self.front_mm, y / 2, z / 2))

    def build(self) -> cq.Shape:
        import cadquery as cq
        from cad.solids import box, cylinder
        b = self.bounds()
        body = box(b)
        r = min(self.size[2] / 2 - 0.5, 6.0)
        body = cq.Workplane().add(body).edges("|X").fillet(r).val()
        # the lens windows: shallow recesses in the front face, one per optical centre
        for s in (1, -1):
            body = body.cut(cylinder(self.lens_window_mm, 1.0, (self.front_mm - 1.0, s * self.baseline_mm / 2, 0),
                                     (1, 0, 0)))
        return body

    def mount_points(self) -> list[tuple[float, float, float]]:
        """The bottom threads (x, y, z) in the camera frame, on the bottom face."""
        b = self.bounds()
        cx = b.centre[0]
        return [(cx + u, v, b.lo[2]) for u, v in self.mount_uv_mm]

    def optical_frames(self) -> dict[str, Pose]:
        """Left and right optical frames (x right, y down, z forward) in the camera frame."""
        return {side: Pose.from_xyz_rpy_deg((0.0, s * self.baseline_mm / 2, 0.0)) @ T_BODY_OPTICAL
                for side, s in (("left", 1.0), ("right", -1.0))}
