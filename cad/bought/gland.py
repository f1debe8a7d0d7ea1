"""A cable gland: the pass-through with strain relief that carries a cable through a wall.

Frame: origin on the axis where the gland's shoulder meets the wall's outer face, z pointing *into* the
case (through the wall); the body and its dome (with the clamping seal) are outside (z < 0), the thread
runs through the wall and the locknut is screwed on it inside, against the wall's inner face. Every size
is ``parts.<gland>.dims`` of the rig (thread, hole, body, locknut, clamping range and the cable it
holds), so the hole a case cuts is the one the gland's table asks for.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from platform_tools.rig import Rig

from cad.bought.base import BoughtPart, envelope, part_colour

if TYPE_CHECKING:
    import cadquery as cq

#: the dome narrows to this fraction of the body's width where the cable leaves it
DOME_TIP_RATIO = 0.6


@dataclass(frozen=True)
class CableGland(BoughtPart):
    thread_d_mm: float = 0.0
    hole_d_mm: float = 0.0
    thread_length_mm: float = 0.0
    body_height_mm: float = 0.0
    nut_d_mm: float = 0.0         # the locknut across its corners: the circle it sweeps when tightened
    nut_height_mm: float = 0.0
    clamp_mm: tuple[float, float] = (0.0, 0.0)
    cable_d_mm: float = 0.0
    wall_mm: float = 0.0          # the wall it is fitted through (the locknut sits on its inner face)

    @classmethod
    def from_rig(cls, rig: Rig, part_id: str) -> "CableGland":
        d = lambda k: rig.dim(part_id, k)
        return cls(part_id, envelope(rig, part_id), part_colour("adapter"), thread_d_mm=d("thread_diameter_mm"),
                   hole_d_mm=d("hole_diameter_mm"), thread_length_mm=d("thread_length_mm"),
                   body_height_mm=d("body_height_mm"), nut_d_mm=d("locknut_across_corners_mm"),
                   nut_height_mm=d("locknut_height_mm"), clamp_mm=(d("clamp_min_mm"), d("clamp_max_mm")),
                   cable_d_mm=d("cable_diameter_mm"))

    @property
    def body_d_mm(self) -> float:
        return self.size[0] / math.cos(math.radians(30))   # across the hex body's corners

    def clamps(self, cable_d_mm: float) -> bool:
        """Whether the seal grips a round cable of this diameter."""
        return self.clamp_mm[0] <= cable_d_mm <= self.clamp_mm[1]

    def build(self) -> cq.Shape:
        """Body, dome, thread and the locknut tightened against the wall's inner face, bored for the cable."""
        import cadquery as cq
        from cad.solids import cone, cylinder
        h = self.body_height_mm
        body = cylinder(self.body_d_mm, h * 0.4, (0, 0, -h * 0.4))
        dome = cone(DOME_TIP_RATIO * self.body_d_mm, self.body_d_mm, h * 0.6, (0, 0, -h))
        thread = cylinder(self.thread_d_mm, self.thread_length_mm)
        nut = cq.Workplane().polygon(6, self.nut_d_mm).extrude(self.nut_height_mm).val() \
            .translate(cq.Vector(0, 0, self.wall_mm))
        shape = body.fuse(dome, thread, nut).clean()
        return shape.cut(cylinder(self.cable_d_mm, h + self.thread_length_mm + 2, (0, 0, -h - 1))).clean()

    def nut_top_mm(self) -> float:
        """How far the locknut reaches into the case from the wall's outer face."""
        return self.wall_mm + self.nut_height_mm
