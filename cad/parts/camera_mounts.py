"""The camera mounts: the ZED X shelf (on two legs either side of its 1/4-20 screw head, on a foot
screwed to the floor) and the thermal bar both Boson heat sinks are screwed onto. One rigid path from
the floor to each camera keeps the CAD extrinsics what the print gives. Modelled in the rig frame."""
from __future__ import annotations

from dataclasses import dataclass

import cadquery as cq

from ..layout import Hole, Layout
from ..geom import Bounds, box, cut_all, fuse_all, one_solid
from .common import PrintSetup, hole_tools


@dataclass(frozen=True)
class ZedMount:
    part_id: str
    shelf: Bounds
    legs: tuple[Bounds, Bounds]
    foot: Bounds
    holes: tuple[Hole, ...]

    def build(self) -> cq.Shape:
        body = fuse_all([box(self.shelf), box(self.legs[0]), box(self.legs[1]), box(self.foot)])
        return one_solid(cut_all(body, hole_tools(self.holes)))


@dataclass(frozen=True)
class ThermalMount:
    part_id: str
    bar: Bounds
    holes: tuple[Hole, ...]

    def build(self) -> cq.Shape:
        return one_solid(cut_all(box(self.bar), hole_tools(self.holes)))


def zed_mount(lay: Layout) -> ZedMount:
    return ZedMount("zed_mount", lay.mounts.zed_shelf, lay.mounts.zed_legs, lay.mounts.zed_foot, lay.holes_for("zed_mount"))


def thermal_mount(lay: Layout) -> ThermalMount:
    return ThermalMount("thermal_mount", lay.mounts.thermal_bar, lay.holes_for("thermal_mount"))


PRINT = {
    "zed_mount": PrintSetup((180.0, 0.0, 0.0), "upside down on its shelf: legs and foot stand up from the bed; on its "
                                                     "back face they floated 2 mm up (the overhang check)"),
    "thermal_mount": PrintSetup((0.0, 0.0, 0.0), "flat, as mounted"),
}
