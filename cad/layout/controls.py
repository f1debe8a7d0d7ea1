"""The controls in the rear wall of the lid (power switch, record button) and the two Wi-Fi antennas
on its roof, each a bought panel part with the pose of its mounting face. Rig frame, mm."""
from __future__ import annotations

from platform_tools.rig import Rig
from platform_tools.rig.frames import Pose

from cad.bought.base import part_of_kind
from cad.bought.panel import PanelPart

from .case import Shell
from .compute import Compute
from .constants import SIDES
from .fits import Fits

#: the switch and the button sit this far outboard of the Orin's side (clear of its port window)
CONTROL_OFFSET_MM = 14.0
#: gap between the rear wall's controls and the antennas' bases
ANTENNA_GAP_MM = 4.0


def place_controls(rig: Rig, fits: Fits, shell: Shell, compute: Compute) -> dict[str, tuple[PanelPart, Pose]]:
    """Node name -> (panel part, pose): the switch on the right and the button on the left of the
    rear wall, at the lid's mid height; an antenna on each side of the roof, just ahead of them."""
    o, w = shell.outer, fits.wall
    lid_mid = (shell.split_z + shell.interior.hi[2]) / 2
    side_y = compute.orin_box.hi[1] + fits.clear + CONTROL_OFFSET_MM
    sw = PanelPart.switch(rig, part_of_kind(rig, "switch"), w)
    bt = PanelPart.button(rig, part_of_kind(rig, "button"), w)
    out = {"power_switch": (sw, Pose.from_xyz_rpy_deg((o.lo[0], -side_y, lid_mid), (0, 0, 180.0))),
           "record_button": (bt, Pose.from_xyz_rpy_deg((o.lo[0], side_y, lid_mid), (0, 0, 180.0)))}
    ant = PanelPart.antenna(rig, part_of_kind(rig, "antenna"), w)
    ax = o.lo[0] + max(sw.size[0], bt.size[0]) + w + fits.clear + ant.size[1] / 2 + ANTENNA_GAP_MM
    for side, s in SIDES:
        out[f"wifi_antenna_{side}"] = (ant, Pose.from_xyz_rpy_deg((ax, s * side_y, o.hi[2]), (0, -90.0, 0)))
    return out
