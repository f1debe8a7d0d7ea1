"""The short leads inside the case, as routes (cad/cable_route.py) for cad/cables.py to lay and check: the
power chain's six leads after the gland (fuse, switch in the lid, cut-off, converter) and the record button's
four jumpers to the Orin's 40-pin header. Where the parts' terminals, lugs and pins are is an estimate (named
at each constant): measure the parts and move these."""
from __future__ import annotations

import numpy as np

from cad.bought.cables import cable_table
from cad.geom import Bounds, Vec3, placed_bounds

from .assembly import Assembly
from .cable_route import BEND_SPARE, Route, _distinct

#: the Orin devkit's 40-pin header, on its front face (+x): across (y, from the centre, towards the fan's
#: side) and up from the devkit's bottom (z); the fans' leads (cad/cables.py) plug in there too. Estimate:
#: measure a devkit.
ORIN_HEADER_Y_MM, ORIN_HEADER_Z_MM = 45.0, 42.0
#: The power chain's leads (``power_leads``). Where each part's terminals are is an estimate (no drawing of the
#: fuse holder, the cut-off module or the TEP 150WI's terminals was read; the switch's tabs are on its body's
#: inner end, their layout not read): measure the parts and move these.
#: the fuse holder's leads leave its body's ends along its axis, this share of its height up (in: the gland's end)
FUSE_TERMINAL_Z_SHARE = 0.6
#: the switch's two .250 tabs on its body's inner end, this far above and below its centre (line above, load
#: below). Were they side by side across the rocker (y), the load tab's lead would pass through the right Wi-Fi
#: antenna's bulkhead, 4 mm in front of the switch's inner end
SWITCH_TAB_DZ_MM = 4.0
#: the cut-off module's screw terminals, top entry on its component block: BAT+ and BAT- at its gland end (-x),
#: LOAD+ and LOAD- at the other, this far in from the block's centre along it (x) and BAT+ / LOAD+ this far
#: outboard (y) of the centre, BAT- on the centre line, LOAD- ``POWER_PAIR_OFFSET_MM`` beyond LOAD+ in x and y
CUTOFF_TERMINAL_DX_MM, CUTOFF_TERMINAL_DY_MM = 10.0, 5.0
#: the converter's input terminals on its rear end (-x) beside the output, this share of the way across it from its
#: outboard face (+IN; -IN ``POWER_PAIR_OFFSET_MM`` inboard of it), at its mid height
CONVERTER_IN_SHARE = 0.25
#: the LOAD+ and LOAD- leads run side by side this far apart (each plane of the pair this far from the other's)
POWER_PAIR_OFFSET_MM = 5.0
#: the two splice leads (fuse and cut-off) end this far above the battery lead's end: the lever splices between
SPLICE_GAP_MM = 10.0
#: a lead from the tray to a part in the lid (the power switch) is bought this much longer, so the lid can be
#: lifted off and set down beside the tray with the lead still on its tab (estimate: about 100 mm up, then over)
LID_OPENING_SLACK_MM = 150.0
#: The record button's leads (``button_leads``): one Dupont jumper per header pin, from the button's lugs in the
#: lid's side wall to the 40-pin header on the Orin's front face.
#: the header's pins at the 0.1 in (2.54 mm) pitch of every 40-pin header: 2 rows of 20, pin n in column (n + 1) // 2
#: (1..20), odd pins in one row, even in the other. Where it stands on the devkit's front face and which way it
#: runs is not in the rig or the reference: the layout's header point (``ORIN_HEADER_Y_MM`` and ``_Z_MM`` on the
#: button's side, where the fan's lead plugs in) is taken as the fans' pins (5 V pin 2, GND pin 6, column 2: see
#: docs/guide/wiring.py), the even row at its height and the odd row this pitch below it, the columns running
#: inboard (towards the devkit's centre line) from there. Estimate: measure a devkit and move these.
HEADER_PITCH_MM = 2.54
HEADER_FAN_COLUMN = 2
#: the header's ground pins (the Jetson 40-pin header has the Raspberry Pi's layout, NVIDIA AGX Orin devkit
#: pinout), and the pins the fans' leads take (5 V, GND; docs/guide/wiring.py draws them): each ground lead goes to
#: the ground pin nearest its signal pin not taken
HEADER_GND_PINS = (6, 9, 14, 20, 25, 30, 34, 39)
HEADER_5V_PIN, HEADER_GND_PIN = 2, 6
HEADER_FAN_PINS = (HEADER_5V_PIN, HEADER_GND_PIN)
#: a rig that numbers the button's pins BCM (recording.button.pin_numbering): the board pin of each BCM GPIO (the
#: Raspberry Pi's table, which Jetson.GPIO's BCM mode follows)
BCM_TO_BOARD = {2: 3, 3: 5, 4: 7, 17: 11, 27: 13, 22: 15, 10: 19, 9: 21, 11: 23, 0: 27, 5: 29, 6: 31, 13: 33, 19: 35,
                26: 37, 14: 8, 15: 10, 18: 12, 23: 16, 24: 18, 25: 22, 8: 24, 7: 26, 1: 28, 12: 32, 16: 36, 20: 38,
                21: 40}
#: the button's four solder lugs on its body's inner end, in one column on its axis (the switch's signal and
#: ground lugs above its LED's + and -), this far apart. Estimate: the lug layout of the generic 16 mm LED button
#: (parts.record_button) is not in the rig; look at the one you buy. The leads leave them along the button's axis.
BUTTON_LUG_PITCH_MM = 4.0


def button_pins(rig) -> list[tuple[str, str, int]]:
    """The record button's leads as (route name, what it joins, board pin of the 40-pin header): the switch to
    ``recording.button.gpio_pin`` and a ground pin, the LED to ``led_pin`` and a ground pin; each ground the
    one nearest its signal pin (by column) that no other lead or fan takes. BCM numbers are turned into board pins."""
    b = rig.desc.recording.button
    def board(p: int) -> int:
        if b.pin_numbering != "BCM":
            return p
        if p not in BCM_TO_BOARD:
            raise ValueError(f"recording.button: BCM {p} is no GPIO of the 40-pin header (pin_numbering: BCM)")
        return BCM_TO_BOARD[p]
    sw, led = board(b.gpio_pin), board(b.led_pin)
    taken = {sw, led, *HEADER_FAN_PINS}
    out = []
    for name, what, pin in (("button_switch", "switch", sw), ("button_led", "LED", led)):
        gnd = min((g for g in HEADER_GND_PINS if g not in taken), key=lambda g: (abs((g + 1) // 2 - (pin + 1) // 2), g))
        taken.add(gnd)
        out += [(name, f"the button's {what} to pin {pin}", pin), (f"{name}_ground", f"the button's {what} ground to "
                                                                   f"pin {gnd} (GND)", gnd)]
    return out


def header_pin(orin_box: Bounds, side: float, pin: int) -> Vec3:
    """Where a lead plugs into pin ``pin`` (board numbering) of the 40-pin header on the Orin's front face, the
    header on the ``side`` (+-1 in y) its fan lead plugs in at (``HEADER_PITCH_MM`` and below: an estimate)."""
    col = (pin + 1) // 2
    y = side * (ORIN_HEADER_Y_MM - (col - HEADER_FAN_COLUMN) * HEADER_PITCH_MM)
    z = orin_box.lo[2] + ORIN_HEADER_Z_MM - (HEADER_PITCH_MM if pin % 2 else 0.0)
    return (float(orin_box.hi[0]), float(y), float(z))


def _button_inward(lay) -> np.ndarray | None:
    """The record button's axis into the case (rig frame), or None when there is no button."""
    if "record_button" not in lay.controls:
        return None
    _, pose = lay.controls["record_button"]
    return pose.R @ np.array([-1.0, 0.0, 0.0])


def button_leads(asm: Assembly) -> list[Route]:
    """The record button's four leads, one Dupont jumper per header pin (``button_pins``): from each lug on the
    button's inner end (``BUTTON_LUG_PITCH_MM``) straight in along its axis to the pin's column (a button in a side
    wall: in front of the devkit's front face) or to the lead's forward leg (a button in the rear wall: beside the
    devkit), then on to the other, and down the forward leg to the pin's row and back into the header on the Orin's
    front face (``header_pin``), plugged in from the front. The leads leave the lugs in one plane, each at its lug's
    height, and come down each in its own column's plane, the forward legs one cable and a clearance apart: the lead
    to the innermost column (it passes the others' columns) furthest forward, and of two pins in one column the
    lower row's ahead of the upper's (its U nests outside the other's), so no lead crosses another. Each turn is
    the jumper's minimum radius, each straight holds its bends (and the housing, at the ends). A lead from the lid
    to the tray is bought ``LID_OPENING_SLACK_MM`` longer, as the switch's are."""
    lay = asm.layout
    n = _button_inward(lay)
    if n is None:
        return []
    k = cable_table().kinds["jumper_wire"]
    R, r, clear = k.min_bend_radius_mm, k.diameter_mm / 2, lay.fits.clear
    orin = lay.compute.orin_box
    bt, pose = lay.controls["record_button"]
    end = -bt.panel_mm - bt.size[0]                    # the body's inner end, in the button's frame
    along_y = abs(n[1]) > 0.5                          # a side wall's button (else the rear wall's, along +x)
    centre = np.asarray(pose.apply(np.array([end, 0.0, 0.0])), dtype=float)
    side = float(np.sign(centre[1])) or 1.0            # the header on the button's side (as its fan's)
    pins = button_pins(lay.rig)
    lugs = [np.asarray(pose.apply(np.array([end, 0.0, (1.5 - i) * BUTTON_LUG_PITCH_MM])), dtype=float)
            for i in range(len(pins))]
    heads = [header_pin(orin, side, pin) for _, _, pin in pins]
    # the forward legs: far enough ahead of the lugs for two bends (the side wall's) or for the housing and one bend
    # (the rear wall's), and of the header for the housing and a bend; then stepped forward pin by pin, from the
    # outermost column's (its upper row first) to the innermost column's lower row, furthest forward
    x0 = max(max(t[0] for t in lugs) + (2 * BEND_SPARE * R if along_y else k.plug_mm + BEND_SPARE * R),
             orin.hi[0] + k.plug_mm + BEND_SPARE * R)
    rank = sorted(range(len(heads)), key=lambda i: (side * heads[i][1], heads[i][2]))
    out = []
    for i, ((name, _, _), t, h) in enumerate(zip(pins, lugs, heads)):
        xf = x0 + (len(heads) - 1 - rank.index(i)) * (2 * r + clear)
        xt, yt, zt = (float(v) for v in t)
        _, yp, zh = h
        first = (xt, yp, zt) if along_y else (xf, yt, zt)
        pts = ((xt, yt, zt), first, (xf, yp, zt), (xf, yp, zh), h)
        lid = LID_OPENING_SLACK_MM if (zt > lay.case.split_z) != (zh > lay.case.split_z) else 0.0
        out.append(Route(name, "jumper_wire", "jumper_wires", ("record_button", "jetson_agx_orin"), _distinct(pts), R,
                         extra_slack_mm=lid))
    return out


def power_leads(asm: Assembly, others: list[Route]) -> list[Route]:
    """The power chain after the gland, one 18 AWG lead per link: from the splice over the battery lead's end
    to the fuse holder's gland end (``fuse_in``); from its other end back into the rear bay, up over the rear
    port band, across the bay, up beside the capture card and forward over the devkit, then round to the
    switch's line tab from in front (``fuse_switch``, into the lid); from the switch's load tab forward, across
    the case over the devkit under the capture card and down onto the cut-off's BAT+ (``switch_cutoff``, from
    the lid); the battery minus from the splice to its BAT- (``battery_minus``); and LOAD+ and LOAD- side by side
    up over the devkit ahead of the card, across, down over the converter, back along it and into its input
    terminals on its rear end (``cutoff_converter_plus`` / ``_minus``). The two leads to the lid are bought
    ``LID_OPENING_SLACK_MM`` longer. Every height and lane is taken from the parts they pass (rig frame, mm)."""
    lay = asm.layout
    k = cable_table().kinds["power_lead"]
    R, r, clear = k.min_bend_radius_mm, k.diameter_mm / 2, lay.fits.clear
    turn = k.plug_mm + BEND_SPARE * R      # a terminal's straight, then a 90 deg bend's tangent
    p, orin, card, inner = lay.power, lay.compute.orin_box, lay.compute.card_box, lay.case.interior
    fuse = placed_bounds(p.fuse.body(), p.fuse_pose)
    z_ft = fuse.lo[2] + FUSE_TERMINAL_Z_SHARE * (fuse.hi[2] - fuse.lo[2])
    y_f = float(p.fuse_pose.t[1])
    # the splice over the battery lead's end (cad/cables.py battery_lead: it ends R above the locknut)
    bat = next(o for o in others if o.name == "battery_lead").points[-1]
    xg, yg, z_s = bat[0], bat[1], bat[2] + SPLICE_GAP_MM
    out = [Route("fuse_in", "power_lead", "power_wire", ("blade_fuse", "cable_gland"),
                 ((fuse.hi[0], y_f, z_ft), (xg, y_f, z_ft), (xg, y_f, z_s)), R, plugs=(True, False))]
    # the switch: its tabs on the body's inner end (+x), a tab's lead runs straight in front of it first
    sw, sw_pose = lay.controls["power_switch"]
    body = placed_bounds(sw.body_bounds(), sw_pose)
    x_sw, y_sw, z_sw = body.hi[0], float(sw_pose.t[1]), float(sw_pose.t[2])
    x_turn = x_sw + turn
    line, load = (x_sw, y_sw, z_sw + SWITCH_TAB_DZ_MM), (x_sw, y_sw, z_sw - SWITCH_TAB_DZ_MM)
    # the rear bay: between the rear wall and the devkit; crossed over the rear leads' highest run (the right
    # USB lead over the converter) and under the switch's body
    x_bay = inner.lo[0] + clear + r + 1.0
    usb_top = max(pt[2] for o in others if o.kind == "usb_lead" for pt in o.points) + \
        cable_table().kinds["usb_lead"].diameter_mm / 2
    z_bay = ((usb_top + clear + r) + (body.lo[2] - clear - r)) / 2
    y_run = (card.lo[1] + body.hi[1]) / 2 if y_sw < 0 else (card.hi[1] + body.lo[1]) / 2
    out.append(Route("fuse_switch", "power_lead", "power_wire", ("blade_fuse", "power_switch"),
                     ((fuse.lo[0], y_f, z_ft), (x_bay, y_f, z_ft), (x_bay, y_f, z_bay), (x_bay, y_run, z_bay),
                      (x_bay, y_run, line[2]), (x_turn, y_run, line[2]), (x_turn, y_sw, line[2]), line), R,
                     extra_slack_mm=LID_OPENING_SLACK_MM))
    # the cut-off's terminals, on top of its component block
    blk = placed_bounds(p.cutoff.components(), p.cutoff_pose)
    cx, cy, zt = blk.centre[0], blk.centre[1], blk.hi[2]
    side = 1.0 if cy > 0 else -1.0
    bat_p = (cx - CUTOFF_TERMINAL_DX_MM, cy + side * CUTOFF_TERMINAL_DY_MM, zt)
    bat_m = (cx - CUTOFF_TERMINAL_DX_MM, cy, zt)
    load_p = (cx + CUTOFF_TERMINAL_DX_MM, cy + side * CUTOFF_TERMINAL_DY_MM, zt)
    # across over the devkit under the capture card, at the load tab's height
    out.append(Route("switch_cutoff", "power_lead", "power_wire", ("power_switch", "undervoltage_cutoff"),
                     (load, (x_turn, y_sw, load[2]), (x_turn, bat_p[1], load[2]), (bat_p[0], bat_p[1], load[2]), bat_p),
                     R, extra_slack_mm=LID_OPENING_SLACK_MM))
    # the battery minus: up from the splice, along to the cut-off's BAT- and down onto it
    z_m = bat_m[2] + turn + BEND_SPARE * R
    out.append(Route("battery_minus", "power_lead", "power_wire", ("cable_gland", "undervoltage_cutoff"),
                     _distinct(((xg, yg, z_s), (xg, yg, z_m), (bat_m[0], yg, z_m), (bat_m[0], bat_m[1], z_m), bat_m)),
                     R, plugs=(False, True)))
    # LOAD+ and LOAD-: up ahead of the card over the devkit, across, down over the converter, back along its top
    # to behind its rear end, down and into its input terminals
    conv = p.converter_box
    d = POWER_PAIR_OFFSET_MM
    sgn = 1.0 if conv.centre[1] < 0 else -1.0          # inboard, from the converter's outboard face
    y_in = (conv.lo[1] + CONVERTER_IN_SHARE * (conv.hi[1] - conv.lo[1])) if sgn > 0 else \
        (conv.hi[1] - CONVERTER_IN_SHARE * (conv.hi[1] - conv.lo[1]))
    z_over = orin.hi[2] + clear + r + 1.0
    z_conv = conv.hi[2] + clear + r
    z_in = conv.centre[2]
    x_rear = conv.lo[0] - turn
    plus = (load_p, (load_p[0], load_p[1], z_over), (load_p[0], y_in, z_over), (load_p[0], y_in, z_conv),
            (x_rear, y_in, z_conv), (x_rear, y_in, z_in), (conv.lo[0], y_in, z_in))
    # LOAD-: each plane of the pair d apart (the x = const part d ahead, the y = const part d inboard), so
    # every bend of one lies in a plane d from the other's
    lm = (load_p[0] + d, load_p[1] + side * d)
    minus = ((lm[0], lm[1], zt), (lm[0], lm[1], z_over + d), (lm[0], y_in + sgn * d, z_over + d),
             (lm[0], y_in + sgn * d, z_conv + d), (x_rear, y_in + sgn * d, z_conv + d), (x_rear, y_in + sgn * d, z_in),
             (conv.lo[0], y_in + sgn * d, z_in))
    out.append(Route("cutoff_converter_plus", "power_lead", "power_wire", ("undervoltage_cutoff", "dc_converter"),
                     plus, R))
    out.append(Route("cutoff_converter_minus", "power_lead", "power_wire", ("undervoltage_cutoff", "dc_converter"),
                     minus, R))
    return out
