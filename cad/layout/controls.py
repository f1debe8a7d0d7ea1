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
from .handles import Handles

#: the switch and the button sit this far outboard of the Orin's side (clear of its port window)
CONTROL_OFFSET_MM = 14.0
#: gap between the rear wall's controls and the antennas' bases
ANTENNA_GAP_MM = 4.0
#: the record button stands this far behind the side grip's front foot pad
BUTTON_PAD_GAP_MM = 3.0


def place_controls(rig: Rig, fits: Fits, shell: Shell, compute: Compute,
                   handles: Handles | None = None) -> dict[str, tuple[PanelPart, Pose]]:
    """Node name -> (panel part, pose): the switch on the right of the rear wall (:func:`switch_pose`);
    the record button in the lid's left wall under the left side grip, just behind its front foot pad
    (raised over the devkit's top when its body would reach in beside the devkit),
    where the hand holding that grip reaches it (the "ergonomics" check; on the rear wall it was 60 mm
    from the nearest grip); an antenna on each side of the roof, ahead of the rear wall's controls."""
    o, w = shell.outer, fits.wall
    lid_mid = (shell.split_z + shell.interior.hi[2]) / 2
    side_y = compute.orin_box.hi[1] + fits.clear + CONTROL_OFFSET_MM
    sw = PanelPart.switch(rig, part_of_kind(rig, "switch"), w)
    bt = PanelPart.button(rig, part_of_kind(rig, "button"), w)
    out = {"power_switch": (sw, switch_pose(rig, fits, shell, compute, sw, side_y)),
           "record_button": (bt, Pose.from_xyz_rpy_deg((o.lo[0], side_y, lid_mid), (0, 0, 180.0)))}
    if handles is not None and "left" in handles.poses:
        front_pad = max((p for p in handles.pads if p.lo[1] >= o.hi[1] - w), key=lambda p: p.hi[0])
        x = front_pad.lo[0] - bt.size[1] / 2 - BUTTON_PAD_GAP_MM
        z = handles.poses["left"].t[2]
        # its body reaches in past the devkit's side: where it stands beside the devkit it passes over its top
        b, inner = compute.orin_box, o.hi[1] - w - bt.size[0]
        if inner < b.hi[1] + fits.clear and x - bt.size[1] / 2 < b.hi[0] + fits.clear:
            z = max(z, b.hi[2] + fits.clear + bt.size[2] / 2)
        out["record_button"] = (bt, Pose.from_xyz_rpy_deg((x, o.hi[1], z), (0, 0, 90.0)))
    ant = PanelPart.antenna(rig, part_of_kind(rig, "antenna"), w)
    ax = o.lo[0] + max(sw.size[0], bt.size[0]) + w + fits.clear + ant.size[1] / 2 + ANTENNA_GAP_MM
    for side, s in SIDES:
        out[f"wifi_antenna_{side}"] = (ant, Pose.from_xyz_rpy_deg((ax, s * side_y, o.hi[2]), (0, -90.0, 0)))
    return out


def switch_pose(rig: Rig, fits: Fits, shell: Shell, compute: Compute, sw: PanelPart, side_y: float) -> Pose:
    """The switch in the lid's rear wall, right of centre: ``side_y`` out, or less where its bezel would
    run onto the wall's corner radius; at the lid's mid height, or higher where its body, reaching in
    behind the wall, would stand over the devkit (it then clears the devkit's top). The capture card on
    the devkit stays beside it (the "interference" check measures what is left). Raises ValueError when the
    raised bezel would run onto the roof's corner radius."""
    o, clear, r = shell.outer, fits.clear, rig.desc.enclosure.corner_radius_mm
    bezel_y, bezel_z = sw.front_mm()
    y = min(side_y, o.hi[1] - r - bezel_y / 2)
    z = (shell.split_z + shell.interior.hi[2]) / 2
    body = sw.body_bounds()                     # yawed 180 deg: its -x reaches in (+x), its y runs along -y
    inner_x, inner_y = o.lo[0] - body.lo[0], -y - body.lo[1]
    b = compute.orin_box
    if inner_x > b.lo[0] - clear and inner_y > b.lo[1] - clear:
        z = max(z, b.hi[2] + clear + sw.size[2] / 2)
    if z + max(bezel_z, sw.size[2]) / 2 > o.hi[2] - r:
        raise ValueError(f"parts.{sw.part_id}.dims.bezel_height_mm: the {bezel_z:g} mm bezel, centred at z {z:.1f} mm "
                         f"so that the body clears the devkit's top, reaches past the lid's roof edge at z "
                         f"{o.hi[2] - r:.1f} mm")
    return Pose.from_xyz_rpy_deg((o.lo[0], -y, z), (0, 0, 180.0))
