"""The handle: an octagonal grip on two posts with screw feet; the same part goes on top and on both
sides. Frame: origin on the pad's top face between the feet, x along the grip, z away from the case,
y across (the part's thickness: the grip's width across flats, so it prints flat with no overhang)."""
from __future__ import annotations

import math
from dataclasses import dataclass

import cadquery as cq

from ..layout import HandleGeometry, Layout
from ..geom import Bounds
from ..solids import box, cut_all, cylinder, fuse_all, one_solid
from .common import PrintSetup


@dataclass(frozen=True)
class Handle:
    part_id: str
    g: HandleGeometry
    hole_d: float
    #: the access hole down through the grip over each inboard foot screw (which sits under the grip):
    #: its screw drops through it and its driver reaches it (the "assembly order" check)
    access_d: float

    def build(self) -> cq.Shape:
        g = self.g
        zc = g.post_height + g.grip_d / 2
        # octagon across flats = grip_d, axis along x
        r = g.grip_d / 2 / math.cos(math.pi / 8)
        pts = [(r * math.cos(math.pi / 8 + k * math.pi / 4), r * math.sin(math.pi / 8 + k * math.pi / 4)) for k in range(8)]
        grip = (cq.Workplane("YZ", origin=(-g.grip_length / 2, 0, zc)).polyline(pts).close()
                .extrude(g.grip_length).val())
        parts = [grip]
        px = g.grip_length / 2 - g.post_width / 2
        for s in (-1, 1):
            parts.append(box(Bounds((s * px - g.post_width / 2, -g.grip_d / 2, 0.0),
                                    (s * px + g.post_width / 2, g.grip_d / 2, zc))))
        parts += [box(b) for b in g.foot_bounds()]
        holes = [cylinder(self.hole_d, g.foot + 0.2, (x, 0, -0.1)) for x in g.foot_screw_x()]
        holes += [cylinder(self.access_d, zc + g.grip_d, (x, 0, g.foot)) for x in g.foot_screw_x()
                  if abs(x) < g.grip_length / 2]
        return one_solid(cut_all(fuse_all(parts), holes))


def handle(lay: Layout) -> Handle:
    rig = lay.rig
    head = rig.dim(rig.desc.enclosure.screw, "head_diameter_mm")
    return Handle("handle", lay.handles.geometry, lay.fits.screw_hole_mm("M3"),
                  access_d=head + 2 * rig.desc.printing.fits.loose_mm)


PRINT = {"handle": PrintSetup((90.0, 0.0, 0.0), "on its side: flat faces top and bottom, octagon grip, no support")}
