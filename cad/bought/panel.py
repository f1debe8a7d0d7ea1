"""Panel-mounted parts: the power switch, the record button and the Wi-Fi antenna bulkheads.

Frame of each: origin at the centre of the panel's outer face, x pointing *out* of the case; the
bezel (or the antenna) is in front (x > 0), the body behind the panel (x < -panel thickness), the
neck through the cut-out in between. ``panel_mm`` is the wall it is mounted in (a design value).
A switch's bezel is its own outline over the panel (``dims.bezel_width_mm`` x ``bezel_height_mm``,
``front_height_mm`` in front), larger than the body that snaps through the cut-out.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from platform_tools.rig import Rig

from cad.geom import Bounds
from cad.bought.base import BoughtPart, envelope, part_colour

if TYPE_CHECKING:
    import cadquery as cq

BEZEL_MM = 2.0   # bezel thickness in front of the panel (drawn only; its outline is the envelope's)


@dataclass(frozen=True)
class PanelPart(BoughtPart):
    panel_mm: float = 2.0
    round_cutout: bool = True
    cutout_mm: tuple[float, float] = (0.0, 0.0)      # (width along y, height along z) or (d, d)
    stick_out_mm: float = BEZEL_MM                   # what is in front of the panel
    stick_out_d_mm: float = 0.0
    bezel_mm: tuple[float, float] | None = None      # (width along y, height along z) in front; None: the body's

    @classmethod
    def switch(cls, rig: Rig, part_id: str, panel_mm: float) -> "PanelPart":
        d = lambda k: rig.dim(part_id, k)
        return cls(part_id, envelope(rig, part_id), part_colour("panel"), panel_mm, False,
                   (d("cutout_width_mm"), d("cutout_height_mm")), stick_out_mm=d("front_height_mm"),
                   bezel_mm=(d("bezel_width_mm"), d("bezel_height_mm")))

    @classmethod
    def button(cls, rig: Rig, part_id: str, panel_mm: float) -> "PanelPart":
        d = rig.dim(part_id, "cutout_diameter_mm")
        return cls(part_id, envelope(rig, part_id), part_colour("panel"), panel_mm, True, (d, d))

    @classmethod
    def antenna(cls, rig: Rig, part_id: str, panel_mm: float) -> "PanelPart":
        d = rig.dim(part_id, "bulkhead_hole_diameter_mm")
        return cls(part_id, envelope(rig, part_id), part_colour("electronics"), panel_mm, True, (d, d),
                   stick_out_mm=rig.dim(part_id, "antenna_length_mm"), stick_out_d_mm=10.0)

    def cutout(self, margin: float = 0.0, depth: float | None = None) -> cq.Shape:
        """The hole in the panel (grown by ``margin`` per side), through the panel thickness."""
        from cad.solids import box, cylinder
        depth = self.panel_mm if depth is None else depth
        w, h = self.cutout_mm
        if self.round_cutout:
            return cylinder(w + 2 * margin, depth + 0.2, (-depth - 0.1, 0, 0), (1, 0, 0))
        return box(Bounds((-depth - 0.1, -w / 2 - margin, -h / 2 - margin), (0.1, w / 2 + margin, h / 2 + margin)))

    def front_mm(self) -> tuple[float, float]:
        """The outline in front of the panel, (width along y, height along z): the bezel's, or the body's."""
        return self.bezel_mm if self.bezel_mm is not None else (self.size[1], self.size[2])

    def bounds(self) -> Bounds:
        x, y, z = self.size
        fy, fz = self.front_mm()
        y, z = max(y, fy), max(z, fz)
        return Bounds((-self.panel_mm - x, -y / 2, -z / 2), (self.stick_out_mm, y / 2, z / 2))

    def body_bounds(self) -> Bounds:
        """The body behind the panel (what must stay clear of the parts inside)."""
        x, y, z = self.size
        return Bounds((-self.panel_mm - x, -y / 2, -z / 2), (-self.panel_mm, y / 2, z / 2))

    def build(self) -> cq.Shape:
        from cad.solids import box, cylinder
        x, y, z = self.size
        w, h = self.cutout_mm
        if self.round_cutout:
            body = cylinder(min(y, z), x, (-self.panel_mm - x, 0, 0), (1, 0, 0))
            neck = cylinder(w, self.panel_mm, (-self.panel_mm, 0, 0), (1, 0, 0))
            front_d = self.stick_out_d_mm or min(y, z)
            front = cylinder(front_d, self.stick_out_mm, (0, 0, 0), (1, 0, 0))
        else:
            body = box(self.body_bounds())
            neck = box(Bounds((-self.panel_mm, -w / 2, -h / 2), (0.0, w / 2, h / 2)))
            fy, fz = self.front_mm()
            front = box(Bounds((0.0, -fy / 2, -fz / 2), (self.stick_out_mm, fy / 2, fz / 2)))
        return body.fuse(neck, front).clean()
