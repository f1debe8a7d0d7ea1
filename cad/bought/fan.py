"""3010 radial blower fan, 5 V.

Frame: origin at the centre; the 30 x 30 faces are normal to z (the inlet, ``inlet_diameter_mm``, is
on +z), the outlet (``outlet_width_mm`` x ``outlet_height_mm``) is on the +x edge, flush with the -y
side. Mounting: two diagonal through holes (``parts.fan_3010_5v.mounting``) along z.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from platform_tools.rig import Rig

from cad.geom import Bounds
from cad.bought.base import BoughtPart, envelope, part_colour

if TYPE_CHECKING:
    import cadquery as cq


@dataclass(frozen=True)
class BlowerFan(BoughtPart):
    outlet_width_mm: float = 0.0
    outlet_height_mm: float = 0.0
    inlet_diameter_mm: float = 0.0
    hole_diameter_mm: float = 0.0
    hole_uv_mm: tuple[tuple[float, float], ...] = ()

    @classmethod
    def from_rig(cls, rig: Rig, part_id: str) -> "BlowerFan":
        m = rig.part(part_id).mounting[0]
        return cls(part_id, envelope(rig, part_id), part_colour("fan"),
                   outlet_width_mm=rig.dim(part_id, "outlet_width_mm"),
                   outlet_height_mm=rig.dim(part_id, "outlet_height_mm"),
                   inlet_diameter_mm=rig.dim(part_id, "inlet_diameter_mm"),
                   hole_diameter_mm=rig.dim(part_id, "hole_diameter_mm"),
                   hole_uv_mm=m.positions_mm)

    @property
    def inlet_area_mm2(self) -> float:
        return math.pi * self.inlet_diameter_mm ** 2 / 4

    def outlet(self) -> Bounds:
        """The outlet opening on the +x edge (a thin box just inside the face)."""
        x, y, _ = self.size
        return Bounds((x / 2 - 0.5, -y / 2, -self.outlet_height_mm / 2),
                      (x / 2, -y / 2 + self.outlet_width_mm, self.outlet_height_mm / 2))

    def holes(self) -> list[tuple[float, float]]:
        return [tuple(p) for p in self.hole_uv_mm]

    def build(self) -> cq.Shape:
        from cad.solids import box, cylinder
        x, y, z = self.size
        body = box(self.bounds())
        body = body.cut(cylinder(self.inlet_diameter_mm, 0.6, (0, 0, z / 2 - 0.6)))
        for u, v in self.holes():
            body = body.cut(cylinder(self.hole_diameter_mm, z, (u, v, -z / 2)))
        return body
