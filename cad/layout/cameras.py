"""The cameras: the ZED X and the two Bosons at the rig's sensor frames (``rig.sensor_frames()``),
each Boson in its copper heat sink; and each camera's field of view, for the windows, the vents and
the checks. Rig frame, mm."""
from __future__ import annotations

import math
from dataclasses import dataclass

from platform_tools.rig import Rig
from platform_tools.rig.frames import Pose

from cad.bought.boson import BosonCore, BosonLens
from cad.bought.zed_x import ZedX
from cad.geom import Bounds, placed_bounds

from .constants import SIDES, Constants


@dataclass(frozen=True)
class ThermalCamera:
    side: str                   # "left" | "right"
    sign: float                 # +1 left, -1 right (the sign of its rig y)
    pose: Pose                  # camera body frame in the rig (from rig.sensor_frames())
    heat_sink: Bounds           # sleeve, fins and base block, rig frame
    fin_bank: Bounds            # the outboard fin bank, rig frame


@dataclass(frozen=True)
class Cameras:
    zed: ZedX
    zed_pose: Pose
    zed_box: Bounds             # the ZED X body, rig frame
    core: BosonCore
    lens: BosonLens
    thermal: dict[str, ThermalCamera]   # by side


def place_cameras(rig: Rig, c: Constants) -> Cameras:
    """Every camera where the rig's sensor frames put it; the heat sinks around the Bosons."""
    d = rig.desc
    frames = rig.sensor_frames()
    zed = ZedX.from_rig(rig, d.sensors.zed_x.part)
    zed_pose = frames["zed_x"].T_rig
    core = BosonCore.from_rig(rig, d.sensors.thermal.part, d.sensors.thermal.lens)
    hs = d.enclosure.heat_sink
    cb = core.bounds()
    # in the camera frame: the sleeve around the body, fins either side, the base block under it
    sleeve = Bounds((cb.lo[0], cb.lo[1] - hs.wall_mm, cb.lo[2] - hs.wall_mm),
                    (cb.hi[0], cb.hi[1] + hs.wall_mm, cb.hi[2] + hs.wall_mm))
    # the front stop ring (``stop_mm`` thick, ahead of the body's front face) is the camera's axial datum
    hs_local = Bounds((sleeve.lo[0], sleeve.lo[1] - hs.fin_height_mm, sleeve.lo[2] - c.heat_sink_base_mm),
                      (sleeve.hi[0] + hs.stop_mm, sleeve.hi[1] + hs.fin_height_mm, sleeve.hi[2]))
    thermal = {}
    for side, s in SIDES:
        pose = frames[f"thermal_{side}"].T_rig
        fin_local = (Bounds((sleeve.lo[0], sleeve.hi[1], sleeve.lo[2]), (sleeve.hi[0], hs_local.hi[1], sleeve.hi[2]))
                     if s > 0 else
                     Bounds((sleeve.lo[0], hs_local.lo[1], sleeve.lo[2]), (sleeve.hi[0], sleeve.lo[1], sleeve.hi[2])))
        thermal[side] = ThermalCamera(side=side, sign=s, pose=pose, heat_sink=placed_bounds(hs_local, pose),
                                      fin_bank=placed_bounds(fin_local, pose))
    return Cameras(zed=zed, zed_pose=zed_pose, zed_box=placed_bounds(zed.bounds(), zed_pose), core=core,
                   lens=BosonLens.from_rig(rig, d.sensors.thermal.lens), thermal=thermal)


def fov_half_angles_deg(rig: Rig) -> dict[str, tuple[float, float]]:
    """Half angles (horizontal, vertical; degrees) of each camera's field of view ("zed_x", "thermal"),
    for frusta and windows. The fisheye Boson gets its diagonal half angle on both axes (a cone that
    holds the whole image)."""
    out = {}
    zm = rig.camera_model(rig.desc.sensors.zed_x.camera_model)
    vz = zm.vfov_deg.value if zm.vfov_deg else zm.hfov_deg.value * zm.height_px / zm.width_px
    out["zed_x"] = (zm.hfov_deg.value / 2, vz / 2)
    tm = rig.camera_model(rig.desc.sensors.thermal.camera_model)
    h = tm.hfov_deg.value / 2
    diag = h * math.hypot(tm.width_px, tm.height_px) / tm.width_px   # equidistant: angle ~ radius
    out["thermal"] = (diag, diag)
    return out
