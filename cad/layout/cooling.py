"""Cooling: a blower fan beside each Boson, standing with its inlet facing out of the case and its
outlet ducted onto the heat sink's outboard fin bank; the plate it is screwed to and the boss behind
it that carries the floor screw. Rig frame, mm."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from platform_tools.rig import Rig
from platform_tools.rig.frames import Pose

from cad.bought.base import part_of_kind
from cad.bought.fan import BlowerFan
from cad.geom import Bounds, placed_bounds

from .cameras import Cameras
from .constants import Constants
from .fits import Fits

#: the duct's end faces are modelled as boxes this thin (they only mark where the duct starts and ends)
DUCT_FACE_MM = 0.01
#: the fan plate runs on this far behind the fan: room for the boss with the floor screw
PLATE_BEHIND_FAN_MM = 12.0
#: wall beside the boss's insert, beyond the printer's minimum wall, on each side
BOSS_WALL_EXTRA_MM = 1.0


@dataclass(frozen=True)
class Fan:
    """One side's fan and the faces its duct joins."""
    side: str
    sign: float
    pose: Pose                  # the fan's frame in the rig
    box: Bounds                 # the fan's envelope, rig frame
    duct_in: Bounds             # the fan outlet face
    duct_out: Bounds            # the fin bank entry face
    outlet_area_mm2: float = 0.0   # the fan's outlet opening (BlowerFan.outlet): what its exhaust must pass


@dataclass(frozen=True)
class FanPlate:
    """The printed fan mount's blocks: the plate the fan is screwed to, down to the floor, and the boss
    behind the fan with the floor screw's insert."""
    plate: Bounds
    boss: Bounds


@dataclass(frozen=True)
class Cooling:
    part: BlowerFan
    fans: dict[str, Fan]          # by side
    plates: dict[str, FanPlate]   # by side


def place_fans(rig: Rig, c: Constants, fits: Fits, cameras: Cameras) -> tuple[BlowerFan, dict[str, Fan]]:
    """Each fan ahead of nothing but its duct: outlet (local +x) towards the fins, inlet (local +z)
    facing out of the case, ``c.duct_length_mm`` before the heat sink's gap."""
    part = BlowerFan.from_rig(rig, part_of_kind(rig, "fan"))
    fx = part.size[0]
    fans = {}
    for side, t in cameras.thermal.items():
        s = t.sign
        rot = Pose.from_xyz_rpy_deg((0, 0, 0), (-90.0 * s, 0, 0))
        out_local = part.outlet()
        out_centre = rot.apply(np.array(out_local.centre))
        fan_front = t.heat_sink.lo[0] - fits.gap - c.duct_length_mm
        target = np.array([fan_front - fx / 2, t.fin_bank.centre[1], t.fin_bank.centre[2]])
        pose = Pose(rot.R, target - np.array([0.0, out_centre[1], out_centre[2]]))
        box = placed_bounds(part.bounds(), pose)
        out_box = placed_bounds(out_local, pose)
        fin, x_hs = t.fin_bank, t.heat_sink.lo[0] - fits.gap
        fans[side] = Fan(side=side, sign=s, pose=pose, box=box,
                         duct_in=Bounds((box.hi[0], out_box.lo[1], out_box.lo[2]),
                                        (box.hi[0] + DUCT_FACE_MM, out_box.hi[1], out_box.hi[2])),
                         duct_out=Bounds((x_hs - DUCT_FACE_MM, fin.lo[1], fin.lo[2]), (x_hs, fin.hi[1], fin.hi[2])),
                         outlet_area_mm2=out_local.size[1] * out_local.size[2])
    return part, fans


def fan_plates(c: Constants, fits: Fits, fans: dict[str, Fan], floor_z: float) -> dict[str, FanPlate]:
    """The plate inboard of each fan, from the floor (``floor_z``, the interior's) to above the duct,
    and the boss at its back end."""
    boss_w = fits.insert.outer_diameter_mm + 2 * (fits.min_wall + BOSS_WALL_EXTRA_MM)
    out = {}
    for side, f in fans.items():
        inboard = f.box.lo[1] if f.sign > 0 else f.box.hi[1]
        plate_y = (inboard - c.fan_plate_mm, inboard) if f.sign > 0 else (inboard, inboard + c.fan_plate_mm)
        top = max(f.box.hi[2], f.duct_in.hi[2] + c.duct_wall_mm, f.duct_out.hi[2] + c.duct_wall_mm)
        plate = Bounds((f.box.lo[0] - PLATE_BEHIND_FAN_MM, plate_y[0], floor_z), (f.duct_out.lo[0], plate_y[1], top))
        y0 = plate.lo[1] if f.sign > 0 else plate.hi[1] - boss_w
        boss = Bounds((plate.lo[0], y0, floor_z), (f.box.lo[0] - fits.clear, y0 + boss_w, floor_z + fits.insert_plate_mm))
        out[side] = FanPlate(plate=plate, boss=boss)
    return out
