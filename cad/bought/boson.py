"""FLIR Boson 640 core with its 4.9 mm lens: one thermal camera.

Frame: origin at the optical centre, x forward along the optical axis, y left, z up (the rig's
``thermal_left`` / ``thermal_right`` body frames). The lens front is ``optical_centre_behind_front_mm``
of the lens ahead of the origin; the lens barrel runs back to the core's front face; the core body
(21 x 21 x 11) sits behind it. Mounting: the rear M1.6 holes of ``parts.boson_640.mounting`` (listed,
not used: the camera is clamped in its copper heat sink).
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
class BosonCore(BoughtPart):
    """The core body; its frame is the camera's (optical centre), so it needs the lens length."""
    lens_length_mm: float = 0.0
    lens_front_mm: float = 0.0
    usb_clearance_mm: float = 0.0

    @classmethod
    def from_rig(cls, rig: Rig, part_id: str, lens_id: str) -> "BosonCore":
        lens = envelope(rig, lens_id)
        return cls(part_id, envelope(rig, part_id), part_colour("thermal"), lens_length_mm=lens[0],
                   lens_front_mm=rig.dim(lens_id, "optical_centre_behind_front_mm"),
                   usb_clearance_mm=rig.dim(part_id, "usb_connector_clearance_mm"))

    @property
    def front_x(self) -> float:
        return self.lens_front_mm - self.lens_length_mm

    def bounds(self) -> Bounds:
        x, y, z = self.size
        return Bounds((self.front_x - x, -y / 2, -z / 2), (self.front_x, y / 2, z / 2))

    def usb_keepout(self) -> Bounds:
        """Room behind the rear face for the USB plug and its cable."""
        b = self.bounds()
        return Bounds((b.lo[0] - self.usb_clearance_mm, -6.0, -6.0), (b.lo[0], 6.0, 6.0))

    def optical_frames(self) -> dict[str, Pose]:
        return {"optical": T_BODY_OPTICAL}


@dataclass(frozen=True)
class BosonLens(BoughtPart):
    """The lens barrel, from the core's front face to the lens front."""
    front_mm: float = 0.0

    @classmethod
    def from_rig(cls, rig: Rig, part_id: str) -> "BosonLens":
        return cls(part_id, envelope(rig, part_id), part_colour("lens"),
                   front_mm=rig.dim(part_id, "optical_centre_behind_front_mm"))

    @property
    def diameter_mm(self) -> float:
        return max(self.size[1], self.size[2])

    def bounds(self) -> Bounds:
        r = self.diameter_mm / 2
        return Bounds((self.front_mm - self.size[0], -r, -r), (self.front_mm, r, r))

    def build(self) -> cq.Shape:
        from cad.solids import cylinder
        return cylinder(self.diameter_mm, self.size[0], (self.front_mm - self.size[0], 0, 0), (1, 0, 0))
