"""Mounts of the power and compute parts: the Orin standoffs (one part, four placed) and the battery
mount plate between the case floor and the Makita dock adapter."""
from __future__ import annotations

from dataclasses import dataclass

import cadquery as cq

from ..layout import Hole, Layout
from ..geom import Bounds
from ..solids import box, cut_all, cylinder, one_solid
from .common import PrintSetup, hole_tools


@dataclass(frozen=True)
class Standoff:
    """Frame: origin at the centre of its bottom face."""
    part_id: str
    diameter: float
    height: float
    hole_d: float

    def build(self) -> cq.Shape:
        return one_solid(cylinder(self.diameter, self.height).cut(cylinder(self.hole_d, self.height + 0.2, (0, 0, -0.1))))


@dataclass(frozen=True)
class BatteryMount:
    part_id: str
    plate: Bounds
    holes: tuple[Hole, ...]

    def build(self) -> cq.Shape:
        return one_solid(cut_all(box(self.plate), hole_tools(self.holes)))


def standoff(lay: Layout) -> Standoff:
    return Standoff("orin_standoff", lay.c.orin_standoff_diameter_mm, lay.compute.standoff_h, lay.fits.screw_hole_mm("M3"))


def battery_mount(lay: Layout) -> BatteryMount:
    return BatteryMount("battery_mount", lay.power.battery_mount, lay.holes_for("battery_mount"))


PRINT = {
    "orin_standoff": PrintSetup((0.0, 0.0, 0.0), "upright"),
    "battery_mount": PrintSetup((0.0, 0.0, 0.0), "flat"),
}
