"""The computer behind the cameras: the Jetson AGX Orin on printed standoffs, its port panel facing
the rear wall, and the ZED Link Quad capture card above it, high enough over the devkit's own fan
inlet (its top face) for the fan to draw air in round the card's edges, on a hex standoff under each of
its corner holes (the fastener table's standoff for the card's thread, its stock length the gap). Rig
frame, mm."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from platform_tools.rig import Rig
from platform_tools.rig.frames import Pose

from cad.bought.base import part_of_kind
from cad.bought.fasteners import Standoff, fastener_table
from cad.bought.jetson import JetsonOrin
from cad.bought.zed_link import ZedLinkQuad
from cad.geom import Bounds, placed_bounds, pose_xyz

from .cameras import Cameras
from .constants import Constants
from .cooling import FanPlate
from .fits import Fits
from .mounts import CameraMounts


@dataclass(frozen=True)
class Compute:
    orin: JetsonOrin
    orin_pose: Pose
    orin_box: Bounds
    standoff_h: float           # the standoffs' height: the floor to the devkit's underside
    card: ZedLinkQuad
    card_pose: Pose
    card_box: Bounds
    fan_diameter: float = 0.0   # the devkit's own fan, drawing from its top face (parts.jetson_agx_orin.dims)
    fan_hub: float = 0.0
    card_gap: float = 0.0       # the devkit's top to the card's underside: the fan inlet's clear height
    card_standoff: Standoff | None = None      # the card's standoffs (one spec), the gap long
    card_standoff_poses: tuple[Pose, ...] = ()  # each on the devkit's top, under a card hole


def fan_inlet_gap_mm(rig: Rig, fits: Fits) -> float:
    """The clear height the devkit's fan needs over its inlet: ``inlet_gap_ratio`` x its diameter
    (D/4: the ring of air pi D h entering round the fan's rim is then its disc pi D^2 / 4), never less
    than the component clearance."""
    orin = part_of_kind(rig, "computer")
    return max(fits.clear, rig.desc.enclosure.vents.inlet_gap_ratio * rig.dim(orin, "fan_diameter_mm"))


def place_compute(rig: Rig, c: Constants, fits: Fits, cameras: Cameras, mounts: CameraMounts,
                  plates: dict[str, FanPlate]) -> Compute:
    """The Orin right behind the rearmost camera part (ZED X, its mount, the fan plates), standing on
    standoffs tall enough for the floor screws' heads; the capture card over it, ``fan_inlet_gap_mm``
    above its top or more (it stood 1 mm above it, on the fan's inlet): the shortest stock standoff of
    that height, one under each of its holes; flush with its rear face."""
    clear = fits.clear
    orin = JetsonOrin.from_rig(rig, part_of_kind(rig, "computer"))
    cam_back = min([cameras.zed_box.lo[0] - clear, mounts.zed_foot.lo[0] - clear]
                   + [p.plate.lo[0] - fits.gap for p in plates.values()])
    standoff_h = max(c.orin_standoff_min_mm, rig.dim(rig.desc.enclosure.screw, "head_height_mm") + 2 * clear)
    orin_pose = pose_xyz(cam_back - orin.size[0] / 2, 0.0, mounts.floor_z + standoff_h)
    orin_box = placed_bounds(orin.bounds(), orin_pose)
    card = ZedLinkQuad.from_rig(rig, rig.desc.sync.source_part)
    so = fastener_table().standoff(card.thread)
    gap = so.pick_length(fan_inlet_gap_mm(rig, fits))
    standoff = Standoff.from_rig(rig, so.part, card.thread, gap)
    # flush with the devkit's rear: raised over the fan, its front socket needs the room ahead of it for
    # the GMSL2 coax's S-bend up from the ZED X (centred on the devkit, the bend did not fit: cad/cables.py)
    card_pose = pose_xyz(orin_box.lo[0] + card.size[0] / 2, 0.0, orin_box.hi[2] + gap)
    feet = tuple(pose_xyz(*card_pose.apply(np.array(pt))[:2], orin_box.hi[2]) for pt in card.mount_points())
    return Compute(orin=orin, orin_pose=orin_pose, orin_box=orin_box, standoff_h=standoff_h, card=card,
                   card_pose=card_pose, card_box=placed_bounds(card.bounds(), card_pose),
                   fan_diameter=rig.dim(orin.part_id, "fan_diameter_mm"),
                   fan_hub=rig.dim(orin.part_id, "fan_hub_diameter_mm"), card_gap=gap,
                   card_standoff=standoff, card_standoff_poses=feet)
