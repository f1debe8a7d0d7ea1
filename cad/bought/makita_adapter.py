"""Makita 18 V LXT dock adapter: the plate with the T-slot rails the battery slides into.

Frame: origin at the centre of its bottom face (where the battery's top face meets it); the plate is
above (z > 0). The T-slot (``t_slot_width_mm`` x ``t_slot_depth_mm``) runs along x in the bottom face.
Its top face is fixed by M3 screws (the adapter's own threads; positions are a design estimate).
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
class MakitaAdapter(BoughtPart):
    t_slot_width_mm: float = 0.0
    t_slot_depth_mm: float = 0.0
    rail_engagement_mm: float = 0.0

    @classmethod
    def from_rig(cls, rig: Rig, part_id: str) -> "MakitaAdapter":
        return cls(part_id, envelope(rig, part_id), part_colour("adapter"),
                   t_slot_width_mm=rig.dim(part_id, "t_slot_width_mm"),
                   t_slot_depth_mm=rig.dim(part_id, "t_slot_depth_mm"),
                   rail_engagement_mm=rig.dim(part_id, "rail_engagement_mm"))

    def bounds(self) -> Bounds:
        x, y, z = self.size
        return Bounds((-x / 2, -y / 2, 0.0), (x / 2, y / 2, z))

    def build(self) -> cq.Shape:
        from cad.solids import box
        x, y, _ = self.size
        slot = Bounds((-x / 2, -self.t_slot_width_mm / 2, 0.0), (x / 2, self.t_slot_width_mm / 2,
                                                                 self.t_slot_depth_mm))
        return box(self.bounds()).cut(box(slot))
