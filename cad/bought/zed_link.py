"""Stereolabs ZED Link Quad capture card (GMSL2), carried on the Orin devkit on four standoffs.

Frame: origin at the centre of its bottom face. Its envelope is its board (``board_thickness_mm``)
and the block of its components and sockets above it, with a copper-free ring (``hole_keepout_mm``)
kept clear over each corner hole (``mounting``, face bottom) for the screw head and its driver. The
holes, like the envelope and its placement on the devkit, are estimates (see docs/cad.md).
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
class ZedLinkQuad(BoughtPart):
    board_mm: float = 1.6
    hole_d_mm: float = 2.7
    keepout_mm: float = 6.0
    mount_uv_mm: tuple[tuple[float, float], ...] = ()
    thread: str = "M2.5"

    @classmethod
    def from_rig(cls, rig: Rig, part_id: str) -> "ZedLinkQuad":
        m = next(m for m in rig.part(part_id).mounting if m.face.value == "bottom")
        return cls(part_id, envelope(rig, part_id), part_colour("card"),
                   board_mm=rig.dim(part_id, "board_thickness_mm"), hole_d_mm=rig.dim(part_id, "hole_diameter_mm"),
                   keepout_mm=rig.dim(part_id, "hole_keepout_mm"),
                   mount_uv_mm=tuple(tuple(p) for p in m.positions_mm), thread=m.thread)

    def bounds(self) -> Bounds:
        x, y, z = self.size
        return Bounds((-x / 2, -y / 2, 0.0), (x / 2, y / 2, z))

    def mount_points(self) -> list[tuple[float, float, float]]:
        """The corner holes, on the board's underside (where each standoff's top bears)."""
        return [(u, v, 0.0) for u, v in self.mount_uv_mm]

    def build(self) -> cq.Shape:
        from cad.solids import box, cylinder
        x, y, z = self.size
        shape = box(self.bounds())
        for u, v, _ in self.mount_points():
            shape = shape.cut(cylinder(self.hole_d_mm, self.board_mm + 0.2, (u, v, -0.1)))
            shape = shape.cut(cylinder(self.keepout_mm, z, (u, v, self.board_mm)))
        return shape.clean()
