"""Makita 18 V LXT battery (BL1840B class).

Frame: origin at the centre of its top face (where it meets the dock adapter); the body hangs below
(z < 0). It slides out along -x (its ``envelope_mm.x`` is the slide direction).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from platform_tools.rig import Rig

from cad.geom import Bounds
from cad.bought.base import BoughtPart, envelope, part_colour

if TYPE_CHECKING:
    import cadquery as cq


@dataclass(frozen=True)
class MakitaBattery(BoughtPart):
    slide_direction: tuple[float, float, float] = (-1.0, 0.0, 0.0)

    @classmethod
    def from_rig(cls, rig: Rig, part_id: str) -> "MakitaBattery":
        return cls(part_id, envelope(rig, part_id), part_colour("battery"))

    def bounds(self) -> Bounds:
        x, y, z = self.size
        return Bounds((-x / 2, -y / 2, -z), (x / 2, y / 2, 0.0))

    def build(self) -> cq.Shape:
        import cadquery as cq
        from cad.solids import box
        return cq.Workplane().add(box(self.bounds())).edges("|X").fillet(min(self.size[1:]) * 0.08).val()
