"""The computer behind the cameras: the Jetson AGX Orin on printed standoffs, its port panel facing
the rear wall, and the ZED Link Quad capture card above it. Rig frame, mm."""
from __future__ import annotations

from dataclasses import dataclass

from platform_tools.rig import Rig
from platform_tools.rig.frames import Pose

from cad.bought.base import part_of_kind
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


def place_compute(rig: Rig, c: Constants, fits: Fits, cameras: Cameras, mounts: CameraMounts,
                  plates: dict[str, FanPlate]) -> Compute:
    """The Orin right behind the rearmost camera part (ZED X, its mount, the fan plates), standing on
    standoffs tall enough for the floor screws' heads; the capture card on top of it."""
    clear = fits.clear
    orin = JetsonOrin.from_rig(rig, part_of_kind(rig, "computer"))
    cam_back = min([cameras.zed_box.lo[0] - clear, mounts.zed_foot.lo[0] - clear]
                   + [p.plate.lo[0] - fits.gap for p in plates.values()])
    standoff_h = max(c.orin_standoff_min_mm, rig.dim(rig.desc.enclosure.screw, "head_height_mm") + 2 * clear)
    orin_pose = pose_xyz(cam_back - orin.size[0] / 2, 0.0, mounts.floor_z + standoff_h)
    orin_box = placed_bounds(orin.bounds(), orin_pose)
    card = ZedLinkQuad.from_rig(rig, rig.desc.sync.source_part)
    card_pose = pose_xyz(orin_pose.t[0], 0.0, orin_box.hi[2] + clear)
    return Compute(orin=orin, orin_pose=orin_pose, orin_box=orin_box, standoff_h=standoff_h, card=card,
                   card_pose=card_pose, card_box=placed_bounds(card.bounds(), card_pose))
