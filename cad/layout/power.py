"""Power: the DC-DC converter on the right wall, the fuse on the floor beside the Orin, and the Makita
battery under the case in its dock adapter, screwed through a printed mount plate to the floor.
Rig frame, mm."""
from __future__ import annotations

from dataclasses import dataclass

from platform_tools.rig import Rig
from platform_tools.rig.frames import Pose

from cad.bought.base import part_of_kind
from cad.bought.electronics import BoxPart
from cad.bought.makita_adapter import MakitaAdapter
from cad.bought.makita_battery import MakitaBattery
from cad.geom import Bounds, placed_bounds, pose_xyz

from .case import Shell
from .compute import Compute
from .fits import Fits


@dataclass(frozen=True)
class Power:
    converter: BoxPart
    converter_pose: Pose
    fuse: BoxPart
    fuse_pose: Pose
    adapter: MakitaAdapter
    adapter_pose: Pose
    battery: MakitaBattery
    battery_pose: Pose
    battery_mount: Bounds       # the plate between the case floor and the dock adapter

    @property
    def converter_box(self) -> Bounds:
        return placed_bounds(self.converter.bounds(), self.converter_pose)


def place_power(rig: Rig, fits: Fits, shell: Shell, compute: Compute) -> Power:
    """The converter standing on the right wall beside the Orin, the fuse beside it on the floor, the
    battery dock centred under the Orin with the battery's rear end flush with the dock's."""
    clear, floor_z = fits.clear, shell.interior.lo[2]
    orin_box, orin_x = compute.orin_box, compute.orin_pose.t[0]
    conv = BoxPart.from_rig(rig, part_of_kind(rig, "converter"))
    cx, cy, _ = conv.size
    conv_pose = Pose.from_xyz_rpy_deg((orin_box.hi[0] - cx / 2, shell.interior.lo[1], floor_z + clear + cy / 2),
                                      (-90.0, 0, 0))
    fuse = BoxPart.from_rig(rig, part_of_kind(rig, "fuse"))
    fuse_pose = pose_xyz(orin_box.lo[0] + fuse.size[0] / 2 + clear, orin_box.hi[1] + clear + fuse.size[1] / 2, floor_z)
    adapter = MakitaAdapter.from_rig(rig, part_of_kind(rig, "battery_adapter"))
    battery = MakitaBattery.from_rig(rig, part_of_kind(rig, "battery"))
    ax, ay, az = adapter.size
    floor_out = shell.outer.lo[2]
    mount = Bounds((orin_x - ax / 2, -ay / 2, floor_out - fits.insert_plate_mm), (orin_x + ax / 2, ay / 2, floor_out))
    adapter_pose = pose_xyz(orin_x, 0.0, mount.lo[2] - az)
    battery_pose = pose_xyz(orin_x + ax / 2 - battery.size[0] / 2, 0.0, adapter_pose.t[2])
    return Power(converter=conv, converter_pose=conv_pose, fuse=fuse, fuse_pose=fuse_pose, adapter=adapter,
                 adapter_pose=adapter_pose, battery=battery, battery_pose=battery_pose, battery_mount=mount)
