"""Cooling: the machined copper heat sink clamped around each Boson, and the printed fan mount that
holds a 3010 blower and ducts its outlet over the outboard fin bank.

Heat sink (camera frame, machined, one design for both cameras): a sleeve whose bore is the Boson
body (the contact faces), ``fin_count`` horizontal fins on each side, and a base block under the
sleeve with two tapped M3 holes (the contact face with the thermal bar).
Fan mount (rig frame, one per side, mirror images): the plate the fan is screwed to, a tapered duct
from the fan outlet to the fin bank, and a boss behind the fan with the floor screw's insert.
"""
from __future__ import annotations

from dataclasses import dataclass

import cadquery as cq

from ..layout import Hole, Layout
from ..geom import Bounds
from ..solids import box, cut_all, cylinder, fuse_all, one_solid
from .common import PrintSetup, hole_tools


@dataclass(frozen=True)
class HeatSink:
    part_id: str
    body: Bounds            # the Boson body: the bore
    wall: float
    fins: int
    fin_t: float
    fin_h: float
    base: float
    holes: tuple[Hole, ...]  # in the camera frame
    #: the front stop (cad/datums.py): a ring ``stop`` thick ahead of the bore, ``stop_bore`` across for the lens
    stop: float = 0.0
    stop_bore: float = 0.0

    def build(self) -> cq.Shape:
        b, w = self.body, self.wall
        sleeve = Bounds((b.lo[0], b.lo[1] - w, b.lo[2] - w), (b.hi[0], b.hi[1] + w, b.hi[2] + w))
        parts = [box(sleeve), box(Bounds((b.lo[0], sleeve.lo[1], sleeve.lo[2] - self.base), (b.hi[0], sleeve.hi[1], sleeve.lo[2])))]
        if self.stop > 0:
            ring = Bounds((b.hi[0] - 0.5, sleeve.lo[1], sleeve.lo[2] - self.base), (b.hi[0] + self.stop, sleeve.hi[1], sleeve.hi[2]))
            parts.append(box(ring).cut(cylinder(self.stop_bore, self.stop + 1.0, (b.hi[0] - 0.5, 0, 0), (1, 0, 0))))
        height = sleeve.size[2]
        pitch = (height - self.fin_t) / max(self.fins - 1, 1)
        for k in range(self.fins):
            z0 = sleeve.lo[2] + k * pitch
            for y0, y1 in ((sleeve.hi[1] - 0.5, sleeve.hi[1] + self.fin_h), (sleeve.lo[1] - self.fin_h, sleeve.lo[1] + 0.5)):
                parts.append(box(Bounds((b.lo[0], y0, z0), (b.hi[0], y1, z0 + self.fin_t))))
        shape = fuse_all(parts).cut(box(b))
        return one_solid(cut_all(shape, hole_tools(self.holes)))

    def contact_area_mm2(self) -> float:
        """Bore faces touching the Boson body (four sides)."""
        x, y, z = self.body.size
        return 2 * x * (y + z)


def heat_sink(lay: Layout) -> HeatSink:
    hs = lay.rig.desc.enclosure.heat_sink
    t = lay.cameras.thermal["left"]
    # the tapped holes are the same in both cameras' frames (the design is symmetric)
    holes = tuple(Hole("heat_sink", tuple(t.pose.inverse().apply(h.origin)), tuple(t.pose.inverse().rotate(h.direction)),
                       h.diameter, h.depth) for h in lay.holes_for("heat_sink_left"))
    return HeatSink("heat_sink", lay.cameras.core.bounds(), hs.wall_mm, hs.fin_count, hs.fin_thickness_mm, hs.fin_height_mm,
                    lay.c.heat_sink_base_mm, holes, stop=hs.stop_mm,
                    stop_bore=lay.cameras.lens.diameter_mm + 2 * lay.rig.desc.printing.fits.sliding_mm)


@dataclass(frozen=True)
class FanMount:
    part_id: str
    plate: Bounds
    boss: Bounds
    duct_in: Bounds
    duct_out: Bounds
    duct_wall: float
    holes: tuple[Hole, ...]

    def build(self) -> cq.Shape:
        duct = self._duct()
        body = fuse_all([box(self.plate), box(self.boss), duct])
        return one_solid(cut_all(body, hole_tools(self.holes)))

    def _duct(self) -> cq.Shape:
        a, b, w = self.duct_in, self.duct_out, self.duct_wall
        x0, x1 = a.hi[0] - 0.01, b.lo[0]

        def rect_at(x: float, grow: float):
            f = (x - x0) / (x1 - x0)
            cy = a.centre[1] + f * (b.centre[1] - a.centre[1])
            cz = a.centre[2] + f * (b.centre[2] - a.centre[2])
            wy = a.size[1] + f * (b.size[1] - a.size[1]) + 2 * grow
            wz = a.size[2] + f * (b.size[2] - a.size[2]) + 2 * grow
            return cq.Wire.makePolygon([cq.Vector(x, cy + sy * wy / 2, cz + sz * wz / 2)
                                        for sy, sz in ((-1, -1), (1, -1), (1, 1), (-1, 1))], close=True)

        outer = cq.Solid.makeLoft([rect_at(x0, w), rect_at(x1, w)], True)
        # the inner passage is the same taper run 0.5 mm past both ends, so the duct is open
        inner = cq.Solid.makeLoft([rect_at(x0 - 0.5, 0.0), rect_at(x1 + 0.5, 0.0)], True)
        return outer.cut(inner)


def fan_mount(lay: Layout, side: str) -> FanMount:
    f, p = lay.cooling.fans[side], lay.cooling.plates[side]
    return FanMount(f"fan_mount_{side}", p.plate, p.boss, f.duct_in, f.duct_out, lay.c.duct_wall_mm,
                    lay.holes_for(f"fan_mount_{side}"))


PRINT = {
    "fan_mount_left": PrintSetup((0.0, 0.0, 0.0), "as mounted: plate and duct stand up; on its plate the duct's "
                                                  "10 x 27 mm side floated (the overhang check)"),
    "fan_mount_right": PrintSetup((0.0, 0.0, 0.0), "as mounted: plate and duct stand up; on its plate the duct's "
                                                   "10 x 27 mm side floated (the overhang check)"),
}
