"""The camera mounts: the thermal bar under both heat sinks (it sets the interior floor), and the ZED X
mount: a shelf under the camera on two legs either side of its 1/4-20 screw head, on a foot screwed to
the floor, with a registration lip behind the camera (its anti-rotation datum). Rig frame, mm."""
from __future__ import annotations

from dataclasses import dataclass

from platform_tools.rig import Rig

from cad.geom import Bounds

from .cameras import Cameras
from .constants import Constants
from .cooling import Fan
from .fits import Fits
from .screws import zed_screw

#: the ZED shelf runs on this far beyond each leg (across the rig)
ZED_SHELF_OVERHANG_MM = 6.0
#: the ZED legs and foot, along x (the depth of the H profile)
ZED_LEG_DEPTH_MM = 14.0
#: the ZED foot runs on this far beyond each leg: room for its two floor screws
ZED_FOOT_OVERHANG_MM = 10.0
#: the registration lip behind the ZED X (its anti-rotation datum, cad/datums.py): thickness along x, and
#: how far it rises above the shelf up the camera's back face (low: clear of the GMSL2 connector above it)
ZED_LIP_THICKNESS_MM = 3.0
ZED_LIP_HEIGHT_MM = 4.0


@dataclass(frozen=True)
class CameraMounts:
    thermal_bar: Bounds         # under both heat sinks, standing on the floor
    zed_shelf: Bounds
    zed_legs: tuple[Bounds, Bounds]   # left (+y), right (-y)
    zed_foot: Bounds
    zed_lip: Bounds             # the registration lip the ZED X's back face rests against (its x and yaw datum)

    @property
    def floor_z(self) -> float:
        """The interior floor (rig z, mm): where the thermal bar stands."""
        return self.thermal_bar.lo[2]


def thermal_bar(fits: Fits, cameras: Cameras, fans: dict[str, Fan]) -> Bounds:
    """The bar under both heat sinks, an insert plate thick, reaching down to the floor when the fans
    need the floor lower than that."""
    hs_all = [t.heat_sink for t in cameras.thermal.values()]
    top = min(b.lo[2] for b in hs_all)
    bar = Bounds((min(b.lo[0] for b in hs_all), min(b.lo[1] for b in hs_all), top - fits.insert_plate_mm),
                 (max(b.hi[0] for b in hs_all), max(b.hi[1] for b in hs_all), top))
    floor_z = min(bar.lo[2], min(f.box.lo[2] for f in fans.values()) - fits.clear)
    return Bounds((bar.lo[0], bar.lo[1], floor_z), bar.hi)


def place_mounts(rig: Rig, c: Constants, fits: Fits, cameras: Cameras, bar: Bounds) -> CameraMounts:
    """The ZED X mount behind the thermal bar, its shelf under the camera."""
    clear, floor_z = fits.clear, bar.lo[2]
    zed_box = cameras.zed_box
    head_d = rig.dim(zed_screw(rig), "head_diameter_mm")
    head_r = head_d / 2 + clear               # the legs stand clear of the screw head
    leg_out = head_d / 2 + clear + c.mount_leg_mm
    # the legs, the foot and the shelf reach back to the lip's back face: one flat back the part prints on
    back = zed_box.lo[0] - ZED_LIP_THICKNESS_MM
    leg_x = (min(back, bar.lo[0] - clear - ZED_LEG_DEPTH_MM), bar.lo[0] - clear)
    shelf_y = head_d / 2 + clear + c.mount_leg_mm + ZED_SHELF_OVERHANG_MM
    shelf = Bounds((leg_x[0], -shelf_y, zed_box.lo[2] - c.mount_shelf_mm),
                   (zed_box.hi[0] - fits.wall - clear, shelf_y, zed_box.lo[2]))
    legs = (Bounds((leg_x[0], head_r, floor_z), (leg_x[1], leg_out, shelf.lo[2])),
            Bounds((leg_x[0], -leg_out, floor_z), (leg_x[1], -head_r, shelf.lo[2])))
    foot_y = head_d / 2 + clear + c.mount_leg_mm + ZED_FOOT_OVERHANG_MM
    foot = Bounds((leg_x[0], -foot_y, floor_z), (leg_x[1], foot_y, floor_z + fits.insert_plate_mm))
    # the lip stands behind the camera's back face, from the shelf's underside to above its top face
    lip = Bounds((zed_box.lo[0] - ZED_LIP_THICKNESS_MM, shelf.lo[1], shelf.lo[2]),
                 (zed_box.lo[0], shelf.hi[1], shelf.hi[2] + ZED_LIP_HEIGHT_MM))
    return CameraMounts(thermal_bar=bar, zed_shelf=shelf, zed_legs=legs, zed_foot=foot, zed_lip=lip)
