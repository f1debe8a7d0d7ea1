"""The camera mounts: the ZED X shelf (on two legs either side of its 1/4-20 screw head, on a foot
screwed to the floor), the thermal bar both Boson heat sinks are screwed onto, and each Boson's
retaining plate (cad/layout/boson_clamp.py) that holds the core forward against its heat sink's front
stop. One rigid path from the floor to each camera keeps the CAD extrinsics what the print gives. The
shelf and the bar are modelled in the rig frame, the retaining plate in the camera's frame."""
from __future__ import annotations

from dataclasses import dataclass

import cadquery as cq

from ..layout import Hole, Layout
from ..layout.boson_clamp import place_boson_clamps
from ..geom import Bounds
from ..solids import box, cut_all, fuse_all, one_solid
from .common import PrintSetup, hole_tools


@dataclass(frozen=True)
class ZedMount:
    part_id: str
    shelf: Bounds
    legs: tuple[Bounds, Bounds]
    foot: Bounds
    holes: tuple[Hole, ...]
    lip: Bounds | None = None   # the registration lip behind the camera (cad/datums.py)

    def build(self) -> cq.Shape:
        blocks = [self.shelf, self.legs[0], self.legs[1], self.foot] + ([self.lip] if self.lip is not None else [])
        body = fuse_all([box(b) for b in blocks])
        return one_solid(cut_all(body, hole_tools(self.holes)))


@dataclass(frozen=True)
class ThermalMount:
    part_id: str
    bar: Bounds
    holes: tuple[Hole, ...]

    def build(self) -> cq.Shape:
        return one_solid(cut_all(box(self.bar), hole_tools(self.holes)))


@dataclass(frozen=True)
class RetainingPlate:
    """A Boson's retaining plate in its camera's frame: the inboard leg with its pad and the foot across
    the copper base, less the screws' clearance holes (left and right are mirror images)."""
    part_id: str
    blocks: tuple[Bounds, ...]
    holes: tuple[Hole, ...]     # in the camera frame

    def build(self) -> cq.Shape:
        return one_solid(cut_all(fuse_all([box(b) for b in self.blocks]), hole_tools(self.holes)))


def retaining_plate(lay: Layout, side: str) -> RetainingPlate:
    cl = place_boson_clamps(lay)[side]
    inv = lay.cameras.thermal[side].pose.inverse()
    name = f"boson_clamp_{side}"
    holes = tuple(Hole(name, tuple(inv.apply(h.origin)), tuple(inv.rotate(h.direction)), h.diameter, h.depth)
                  for h in lay.holes_for(name))
    return RetainingPlate(name, cl.blocks, holes)


def zed_mount(lay: Layout) -> ZedMount:
    m = lay.mounts
    return ZedMount("zed_mount", m.zed_shelf, m.zed_legs, m.zed_foot, lay.holes_for("zed_mount"), lip=m.zed_lip)


def thermal_mount(lay: Layout) -> ThermalMount:
    return ThermalMount("thermal_mount", lay.mounts.thermal_bar, lay.holes_for("thermal_mount"))


PRINT = {
    "zed_mount": PrintSetup((0.0, -90.0, 0.0), "on its back face (the lip, shelf, legs and foot share it): every block "
                                                "stands up from the bed; upside down on the shelf the registration lip "
                                                "would hold it 4 mm up"),
    "thermal_mount": PrintSetup((0.0, 0.0, 0.0), "flat, as mounted"),
    **{f"boson_clamp_{side}": PrintSetup((0.0, -90.0, 0.0), "on its back face (where the screw heads sit), pad up: "
                                                             "every face stands up from the bed, the holes print "
                                                             "vertical") for side in ("left", "right")},
}
