"""The key cables as swept paths (issue 16, "Cables"): bend radius, interference and lengths, with a
bend too tight and a cable through a wall each failing the check."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from cad.bought.cables import cable_table
from cad.cables import Route, centreline, path_of, routes, sweep
from cad.solids import bounds_of, box

KINDS = cable_table().kinds


def test_stock_length_rounds_up_and_runs_out():
    k = KINDS["gmsl2_coax"]
    assert k.min_bend_radius_mm == pytest.approx(k.bend_factor * k.diameter_mm)
    first = sorted(k.stock_lengths_mm)[0]
    assert k.bought_length_mm(first - k.service_slack_mm) == first
    assert k.bought_length_mm(first - k.service_slack_mm + 0.1) == sorted(k.stock_lengths_mm)[1]
    assert k.bought_length_mm(max(k.stock_lengths_mm)) is None
    reel = KINDS["sync_pair"]
    assert not reel.stock_lengths_mm and reel.bought_length_mm(101) == math.ceil((101 + reel.service_slack_mm) / 10) * 10


def _l_route(radius, first_leg=40.0, second_leg=40.0, kind="sync_pair"):
    return Route("test_l", kind, None, ("a", "b"), ((0, 0, 0), (first_leg, 0, 0), (first_leg, second_leg, 0)), radius)


def test_length_of_an_l_bend_is_straights_plus_the_quarter_arc():
    r = KINDS["sync_pair"].min_bend_radius_mm
    p = path_of(_l_route(r), KINDS["sync_pair"])
    assert p.length_mm == pytest.approx(2 * (40 - r) + math.pi / 2 * r)
    # OpenCascade's length of the built wire, an independent path to the same number
    assert centreline(_l_route(r)).Length() == pytest.approx(p.length_mm, rel=1e-6)
    assert not p.problems


def test_a_bend_under_the_minimum_fails():
    k = KINDS["sync_pair"]
    p = path_of(_l_route(k.min_bend_radius_mm * 0.5), k)
    assert any("needs at least" in s and f"{k.min_bend_radius_mm:g} mm" in s for s in p.problems), p.problems


def test_a_bend_squeezed_against_its_plug_fails_with_the_radius_it_really_gets():
    k = KINDS["sync_pair"]
    # the first leg holds the plug but only half the bend's tangent length
    leg = k.plug_mm + k.min_bend_radius_mm / 2
    p = path_of(_l_route(k.min_bend_radius_mm, first_leg=leg), k)
    bad = [s for s in p.problems if "too short" in s]
    assert bad and "about 4.8 mm" in bad[0], p.problems      # (leg - plug) / tan(45 deg) = R / 2


def test_swept_cable_is_a_valid_solid_of_its_diameter():
    k = KINDS["gmsl2_coax"]
    r = _l_route(k.min_bend_radius_mm, 60, 60, "gmsl2_coax")
    s = sweep(r, k)
    assert s.isValid() and len(s.Solids()) == 1
    area = math.pi / 4 * k.diameter_mm ** 2
    assert s.Volume() == pytest.approx(area * path_of(r, k).length_mm, rel=1e-3)


@pytest.mark.slow
def test_rig_cables_pass_and_bends_read_back_from_the_wires(asm, results):
    r = results["cables"]
    assert r.ok, r.details[:12]
    rs = routes(asm)
    assert {x.name for x in rs} >= {"gmsl2", "sync_left", "sync_right", "fan_lead_left", "fan_lead_right",
                                    "pigtail_left", "pigtail_right", "battery_lead", "usb_left", "usb_right", "dc_lead"}
    for x in rs:
        arcs = [e for e in centreline(x).Edges() if e.geomType() == "CIRCLE"]
        assert arcs, x.name
        for e in arcs:   # the arc OpenCascade holds, not the number the route was given
            assert e.radius() >= KINDS[x.kind].min_bend_radius_mm - 1e-6, x.name
        assert r.data["lengths"][x.name] == pytest.approx(centreline(x).Length(), abs=0.1)


@pytest.mark.slow
def test_a_cable_through_the_wall_fails(asm):
    from cad.checks import check_cables
    i = asm.layout.case.interior
    y = (i.lo[1] + i.hi[1]) / 2 + 20
    z = (i.lo[2] + asm.layout.case.split_z) / 2
    x = asm.layout.compute.orin_box.hi[0] + 30          # clear of the Orin, through the right side wall
    wall = Route("test_wall", "sync_pair", None, ("a", "b"), ((x, i.lo[1] + 10, z), (x, i.lo[1] - 20, z)),
                 KINDS["sync_pair"].min_bend_radius_mm)
    res = check_cables(asm, only=[wall])
    assert not res.ok
    assert any(p.startswith("cable test_wall") and "case_lower" in p for p in res.details), res.details[:4]
    inside = Route("test_inside", "sync_pair", None, ("a", "b"), ((x, y - 15, z), (x, y + 15, z)), 9.6)   # room for both plugs
    assert check_cables(asm, only=[inside]).ok


@pytest.mark.slow
def test_the_battery_lead_rises_straight_through_the_gland_and_a_tighter_loop_fails(asm):
    """The battery lead (cad/cables.py ``battery_lead``): swept clear of every part, its last bend ending
    below the gland's dome (it enters the seal straight); laid with half its radius, or with its drop
    beside the adapter shortened to one radius, it fails."""
    from cad.cables import battery_lead, cable_report
    lead = battery_lead(asm)
    k = KINDS["battery_lead"]
    assert k.diameter_mm == asm.layout.power.gland.cable_d_mm            # the lead the gland is chosen for
    rep = cable_report(asm, only=[lead])
    assert not rep.problems, rep.problems
    # the wire OpenCascade holds: every arc at the radius, the last one wholly below the dome's tip
    gz = asm.layout.power.gland_pose.t[2] - asm.layout.power.gland.body_height_mm
    arcs = [e for e in centreline(lead).Edges() if e.geomType() == "CIRCLE"]
    assert len(arcs) == 3 and all(e.radius() == pytest.approx(k.min_bend_radius_mm) for e in arcs)
    assert max(v.Z for v in arcs[-1].Vertices()) < gz
    assert rep.paths[0].length_mm == pytest.approx(centreline(lead).Length(), abs=0.1)
    tight = path_of(dataclasses.replace(lead, radius_mm=k.min_bend_radius_mm / 2), k)
    assert any("needs at least 22 mm" in p for p in tight.problems), tight.problems
    p = np.asarray(lead.points)
    short = p.copy()
    short[2:4, 2] += k.min_bend_radius_mm          # the drop beside the adapter one radius instead of two
    squeezed = path_of(dataclasses.replace(lead, points=tuple(map(tuple, short))), k)
    assert any("segment 2" in s and "too short" in s for s in squeezed.problems), squeezed.problems


# ----------------------------------------------------------------------------- the Orin's rear-port leads
def _rear_leads(asm):
    from cad.cables import dc_lead, usb_leads
    return usb_leads(asm) + [dc_lead(asm)]


def _moved(route, dx):
    """The route and its plug bodies moved ``dx`` along x (the rear wall, in effect, moved by -dx)."""
    from cad.geom import Bounds
    pts = tuple((p[0] + dx, p[1], p[2]) for p in route.points)
    env = tuple((w, Bounds((b.lo[0] + dx, b.lo[1], b.lo[2]), (b.hi[0] + dx, b.hi[1], b.hi[2]))) for w, b in route.envelopes)
    return dataclasses.replace(route, points=pts, envelopes=env)


@pytest.mark.slow
def test_the_rear_port_leads_pass_and_their_plugs_stand_clear_of_the_rear_wall(asm):
    """Each Boson's USB lead and the DC lead swept clear of every part and cable, their right-angle plugs' bodies
    in the room between the devkit's port face and the rear wall: the distance OpenCascade measures from each
    plug body to the built tray is at least the component clearance, and the plug's face touches the devkit."""
    from cad.cables import cable_report
    leads = _rear_leads(asm)
    assert {r.name for r in leads} == {"usb_left", "usb_right", "dc_lead"}
    rep = cable_report(asm, only=leads)
    assert not rep.problems, rep.problems
    shapes = {n.name: n.shape(asm.cache) for n in asm.nodes}
    for r in leads:
        assert r.envelopes, r.name
        for what, b in r.envelopes:
            assert box(b).distance(shapes["case_lower"]) >= asm.layout.fits.clear - 1e-6, what
            assert box(b).distance(shapes["jetson_agx_orin"]) < 1e-6, what
        assert r.ends[1 if r.name.startswith("usb") else 0] == "jetson_agx_orin"
    # the USB leads bend at the lead's minimum radius on the wire OpenCascade holds
    for r in leads[:2]:
        arcs = [e for e in centreline(r).Edges() if e.geomType() == "CIRCLE"]
        assert arcs and all(e.radius() == pytest.approx(KINDS["usb_lead"].min_bend_radius_mm) for e in arcs)


def _wire_points(route, n=600):
    """Points along the route's built centre line (OpenCascade's wire, not the waypoints)."""
    w = centreline(route)
    return np.array([tuple(w.positionAt(t)) for t in np.linspace(0.0, 1.0, n)])


@pytest.mark.slow
def test_the_right_usb_lead_passes_over_the_converter_and_comes_down_in_the_rear_bay(asm):
    """The converter (TEP 150-2412WI, 98 mm long) fills the strip beside the devkit from its front face to 18.5 mm
    short of the plug's exit: the right USB lead runs over its top and comes down behind its rear end, in the
    bay. Read on the built wire: the cable's surface is at least a clearance off the converter's box everywhere,
    over its footprint at least a clearance above its top; wherever it is lower than that top, it is behind the
    converter's rear end, between it and the plug's exit. Laid as before (down to the port's height in the lane ahead of the bay),
    the lead runs into the converter, and the cable check names it."""
    from cad.cables import cable_report
    lay = asm.layout
    conv, clear = lay.power.converter_box, lay.fits.clear
    k = KINDS["usb_lead"]
    r, R = k.diameter_mm / 2, k.min_bend_radius_mm
    lead = next(x for x in _rear_leads(asm) if x.name == "usb_right")
    pts = _wire_points(lead)
    gap = np.linalg.norm(np.maximum(np.maximum(np.array(conv.lo) - pts, pts - np.array(conv.hi)), 0.0), axis=1)
    assert gap.min() >= r + clear - 0.05        # the cable's surface a clearance off the converter everywhere
    over = (pts[:, 0] > conv.lo[0]) & (pts[:, 0] < conv.hi[0]) & (pts[:, 1] < conv.hi[1])
    assert over.sum() > 50 and (pts[over, 2] - r).min() >= conv.hi[2] + clear - 1e-3
    below = (pts[:, 2] < conv.hi[2]) & (pts[:, 0] < conv.hi[0])   # down at the converter's height, behind the cameras
    exit_x = lead.points[-1][0]
    assert below.any() and (pts[below, 0] < conv.lo[0] - r - clear).all()
    assert (pts[below, 0] >= exit_x - 1e-3).all()                 # between the plug's exit and the converter
    # the old way into the bay: from the run over the converter down to the port's height ahead of the bay's
    # bend (75 deg, its bends R apart), in the lane it runs in over the converter, then across the bay into the plug
    # (the lead's points: the socket, the climb's two corners, then the run's end over the bay, ...)
    z_run, zp, xc, y_rear = lead.points[2][2], lead.points[-1][2], exit_x, lead.points[3][1]
    assert z_run == pytest.approx(conv.hi[2] + r + clear) and lead.points[3][2] == pytest.approx(z_run)
    x4 = xc + R + R * math.tan(math.radians(37.5)) + clear
    x3 = x4 + (z_run - zp) / math.tan(math.radians(75.0))
    old = dataclasses.replace(lead, points=tuple(lead.points[:3]) + ((x3, y_rear, z_run), (x4, y_rear, zp),
                                                                      (xc, y_rear, zp), lead.points[-1]))
    assert not path_of(old, k).problems     # a well-formed route: what fails it is the part in its way
    rep = cable_report(asm, only=[old])
    assert any(p.startswith("cable usb_right (") and "dc_converter" in p for p in rep.problems), rep.problems


@pytest.mark.slow
def test_a_rear_lead_bent_too_tight_fails(asm):
    k = KINDS["usb_lead"]
    lead = _rear_leads(asm)[0]
    tight = path_of(dataclasses.replace(lead, radius_mm=k.min_bend_radius_mm / 2), k)
    assert any(f"needs at least {k.min_bend_radius_mm:g} mm" in p for p in tight.problems), tight.problems
    # the bay's last bend squeezed: the plug's exit moved up to 5 mm from the lane's corner
    p = list(lead.points)
    p[-1] = (p[-1][0], p[-2][1] - math.copysign(5.0, p[-2][1]), p[-1][2])
    squeezed = path_of(dataclasses.replace(lead, points=tuple(p)), k)
    assert any("too short" in s for s in squeezed.problems), squeezed.problems


@pytest.mark.slow
def test_with_the_rear_wall_where_it_was_the_plugs_and_leads_run_into_it(asm):
    """The rear wall used to stand one clearance behind the port face: every lead moved back by the room the
    wall was moved back for (as if the wall stood where it was) runs into case_lower beside the port window,
    and every plug sticks out through the window, behind the case's outer rear face (the built tray's)."""
    from cad.cables import cable_report
    lay = asm.layout
    back = lay.compute.orin_box.lo[0] - lay.case.interior.lo[0] - lay.fits.clear
    assert back > 10.0
    moved = [_moved(r, -back) for r in _rear_leads(asm)]
    rep = cable_report(asm, only=moved)
    for name in ("usb_left", "usb_right", "dc_lead"):
        assert any(p.startswith(f"cable {name} (") and "case_lower" in p for p in rep.problems), (name, rep.problems)
    rear = bounds_of(next(n for n in asm.nodes if n.name == "case_lower").shape(asm.cache)).lo[0]
    assert all(b.lo[0] < rear for r in moved for _, b in r.envelopes)
    assert all(b.lo[0] > rear for r in _rear_leads(asm) for _, b in r.envelopes)


@pytest.mark.slow
def test_two_cables_over_each_other_fail_and_a_y_harness_shares_its_trunk(asm):
    from cad.cables import cable_report
    dc = _rear_leads(asm)[2]
    twin = dataclasses.replace(dc, name="test_twin", catalogue=None, envelopes=(),
                               points=tuple((p[0], p[1], p[2] + 2.0) for p in dc.points))
    rep = cable_report(asm, only=[dc, twin])
    assert any("cable dc_lead and cable test_twin overlap" in p for p in rep.problems), rep.problems
    syncs = [r for r in routes(asm) if r.name.startswith("sync_")]
    assert len(syncs) == 2 and syncs[0].points[:2] == syncs[1].points[:2]     # one trunk, two branches
    assert not [p for p in cable_report(asm, only=syncs).problems if "overlap" in p]


@pytest.mark.slow
def test_a_usb_plug_longer_than_the_room_behind_the_breakout_is_one_line(asm, monkeypatch):
    """The USB lead's straight plug must fit the room the Boson's breakout leaves behind it (the rig's
    ``usb_connector_clearance_mm``, which the power-parts check keeps clear): a longer one is named."""
    from cad import cables
    room = asm.rig.dim(asm.layout.cameras.core.part_id, "usb_connector_clearance_mm")
    table = cable_table()
    assert KINDS["usb_lead"].plug_mm <= room
    long = dataclasses.replace(table, kinds={**table.kinds, "usb_lead": dataclasses.replace(
        table.kinds["usb_lead"], plug_mm=room + 3)})
    monkeypatch.setattr(cables, "cable_table", lambda: long)
    rep = cables.cable_report(asm, only=[])
    assert rep.problems == [f"cad/bought/cables.yaml: kinds.usb_lead.plug_mm is {room + 3:g} mm but the room behind each "
                            f"breakout is parts.boson_640.dims.usb_connector_clearance_mm = {room:g} mm"]


POWER_LEADS = ("fuse_in", "fuse_switch", "switch_cutoff", "battery_minus", "cutoff_converter_plus",
               "cutoff_converter_minus")


@pytest.mark.slow
def test_the_power_chain_is_routed_clear_with_the_lids_slack(asm, results):
    """The power leads after the gland (gland splice -> fuse -> switch in the lid -> cut-off -> converter, and
    the battery minus to the cut-off) are routes of the cable check: 18 AWG wire, every bend at least 4 x its
    diameter, clear of every part and cable (the rig's check passes with them). Each ends on its parts' faces
    as placed; the two leads to the switch cross the case's split and are bought the lid's opening slack
    longer than their route and the wire's service slack."""
    from cad.cable_leads import LID_OPENING_SLACK_MM
    from cad.cables import cable_lengths
    assert results["cables"].ok, results["cables"].details[:12]
    lay = asm.layout
    rs = {r.name: r for r in routes(asm)}
    assert set(POWER_LEADS) <= set(rs)
    k = KINDS["power_lead"]
    for name in POWER_LEADS:
        r = rs[name]
        assert r.kind == "power_lead" and r.catalogue == "power_wire" and r.radius_mm >= k.min_bend_radius_mm
        assert not path_of(r, k).problems, name
    # ends where the parts are: the fuse holder's body ends, the switch's inner end, the cut-off block's top,
    # the converter's rear end
    from cad.geom import placed_bounds
    p = lay.power
    fuse = placed_bounds(p.fuse.body(), p.fuse_pose)
    sw, pose = lay.controls["power_switch"]
    body = placed_bounds(sw.body_bounds(), pose)
    blk = placed_bounds(p.cutoff.components(), p.cutoff_pose)
    assert rs["fuse_in"].points[0][0] == pytest.approx(fuse.hi[0]) and rs["fuse_switch"].points[0][0] == pytest.approx(fuse.lo[0])
    assert rs["fuse_switch"].points[-1][0] == pytest.approx(body.hi[0]) == rs["switch_cutoff"].points[0][0]
    for name in ("switch_cutoff", "battery_minus"):
        assert rs[name].points[-1][2] == pytest.approx(blk.hi[2])
    for name in ("cutoff_converter_plus", "cutoff_converter_minus"):
        assert rs[name].points[0][2] == pytest.approx(blk.hi[2]) and rs[name].points[-1][0] == pytest.approx(p.converter_box.lo[0])
    # the switch's leads run from the tray (z under the split) to the lid (over it)
    split = lay.case.split_z
    for name in ("fuse_switch", "switch_cutoff"):
        zs = [pt[2] for pt in rs[name].points]
        assert min(zs) < split < max(zs)
    rows = {c["route"]: c for c in cable_lengths(asm)}
    for name in POWER_LEADS:
        lid = LID_OPENING_SLACK_MM if name in ("fuse_switch", "switch_cutoff") else 0.0
        c = rows[name]
        assert c["slack_mm"] == k.service_slack_mm + lid
        assert c["bought_mm"] == math.ceil((c["route_mm"] + k.service_slack_mm + lid) / 10.0) * 10.0
        assert c["bought_mm"] >= path_of(rs[name], k).length_mm + k.service_slack_mm + lid


@pytest.mark.slow
def test_a_power_lead_under_the_devkits_top_fails(asm):
    """The switch-to-cut-off lead crosses the case between the devkit's top and the capture card: laid 10 mm
    lower it runs through the devkit, and the check names both."""
    from cad.checks import check_cables
    r = next(x for x in routes(asm) if x.name == "switch_cutoff")
    z = r.points[1][2] - 10.0
    low = dataclasses.replace(r, name="test_low", points=(r.points[0],) + tuple((x, y, z) for x, y, _ in r.points[1:4])
                              + (r.points[4],))
    res = check_cables(asm, only=[low])
    assert not res.ok
    assert any(p.startswith("cable test_low") and "jetson_agx_orin" in p for p in res.details), res.details[:4]
    assert check_cables(asm, only=[r]).ok


@pytest.mark.slow
def test_the_power_wire_is_bought_from_the_routes(asm):
    """The BOM's power_wire line counts one piece per power lead route, cut to the longest one's length
    (route + slack, and the lid's slack on the switch's leads): no typed-in 2 m."""
    _bought_from_routes(asm, "power_wire", POWER_LEADS)


def _bought_from_routes(asm, catalogue: str, leads):
    """Assert the BOM's ``catalogue`` line counts one piece per route bought as it (as many as ``leads``), at
    the length the longest needs; returns the BOM."""
    from bom.bom import build_bom
    from bom.catalogue import load_catalogue
    from cad.cables import cable_lengths
    bom = build_bom(asm, load_catalogue(asm.rig, None))
    ln = bom.line(catalogue)
    mine = [c for c in cable_lengths(asm) if c["catalogue"] == catalogue]
    assert ln.source == "cable routes" and ln.unit == "pcs" and ln.quantity == len(mine) == len(leads)
    longest = max(c["bought_mm"] for c in mine)
    assert f"{longest:g} mm" in ln.part_number
    return bom


# ----------------------------------------------------------------------------- the record button's leads
BUTTON_LEADS = ("button_switch", "button_switch_ground", "button_led", "button_led_ground")


@pytest.mark.slow
def test_the_record_buttons_leads_are_routed_clear_from_its_lugs_to_the_header(asm, results):
    """The record button's switch and LED leads (one Dupont jumper per header pin) are routes of the cable check:
    from the button's inner end in the lid's side wall, across the case's split, to the 40-pin header on the Orin's
    front face; every bend at the jumper's minimum radius on the wire OpenCascade holds, clear of every part and
    cable (the rig's check passes with them). Their pins are the rig's (recording.button), each ground a ground pin
    of the header, none the fans'; each is bought the lid's opening slack longer, at a stock length."""
    from cad.cable_leads import HEADER_GND_PINS, LID_OPENING_SLACK_MM, button_pins
    from cad.cables import cable_lengths
    from cad.geom import placed_bounds
    from docs.guide.wiring import HEADER_5V_PIN, HEADER_GND_PIN
    assert results["cables"].ok, results["cables"].details[:12]
    lay = asm.layout
    rs = {r.name: r for r in routes(asm)}
    assert set(BUTTON_LEADS) <= set(rs)
    k = KINDS["jumper_wire"]
    b = asm.rig.desc.recording.button
    pins = {name: pin for name, _, pin in button_pins(asm.rig)}
    assert b.pin_numbering == "BOARD" and pins["button_switch"] == b.gpio_pin and pins["button_led"] == b.led_pin
    assert {pins["button_switch_ground"], pins["button_led_ground"]} <= set(HEADER_GND_PINS)
    assert len(set(pins.values()) | {HEADER_5V_PIN, HEADER_GND_PIN}) == 6            # no pin taken twice
    bt, pose = lay.controls["record_button"]
    body = placed_bounds(bt.body_bounds(), pose)
    orin, split = lay.compute.orin_box, lay.case.split_z
    heads = set()
    for name in BUTTON_LEADS:
        r = rs[name]
        assert r.kind == "jumper_wire" and r.catalogue == "jumper_wires" and r.ends == ("record_button", "jetson_agx_orin")
        assert not path_of(r, k).problems, name
        arcs = [e for e in centreline(r).Edges() if e.geomType() == "CIRCLE"]
        assert len(arcs) == 3 and all(e.radius() >= k.min_bend_radius_mm - 1e-6 for e in arcs), name
        (x0, y0, z0), (x1, y1, z1) = r.points[0], r.points[-1]
        # on the button's inner end, inside its footprint; on the devkit's front face, plugged in from the front
        assert y0 == pytest.approx(body.lo[1]) and body.lo[0] < x0 < body.hi[0] and body.lo[2] < z0 < body.hi[2]
        assert x1 == pytest.approx(orin.hi[0]) and orin.lo[1] < y1 < orin.hi[1] and orin.lo[2] < z1 < orin.hi[2]
        assert r.points[-2][0] > x1 and r.points[-2][1:] == r.points[-1][1:]
        assert z0 > split > z1                     # from the lid to the tray
        heads.add((round(y1, 3), round(z1, 3)))
    assert len(heads) == 4                          # four pins, 2.54 mm apart at least
    rows = {c["route"]: c for c in cable_lengths(asm)}
    for name in BUTTON_LEADS:
        c = rows[name]
        assert c["slack_mm"] == k.service_slack_mm + LID_OPENING_SLACK_MM
        assert c["bought_mm"] in k.stock_lengths_mm
        assert c["bought_mm"] >= path_of(rs[name], k).length_mm + k.service_slack_mm + LID_OPENING_SLACK_MM


@pytest.mark.slow
def test_a_button_lead_through_the_devkit_or_bent_too_tight_fails(asm):
    """The lowest button lead (the LED's ground) runs in from the button just ahead of the devkit's front face,
    under its top: laid 10 mm further back, its run from the button passes through the devkit, and the check names
    it. At half its radius, or with the U's forward leg one radius from the lane (too short for its two bends),
    its bends fail."""
    from cad.checks import check_cables
    k = KINDS["jumper_wire"]
    r = next(x for x in routes(asm) if x.name == "button_led_ground")
    assert check_cables(asm, only=[r]).ok
    p = list(r.points)
    back = dataclasses.replace(r, name="test_back", points=tuple((x - 10.0 if i < 2 else x, y, z)
                                                                   for i, (x, y, z) in enumerate(p)))
    assert not path_of(back, k).problems           # a well-formed route: what fails it is the part in its way
    res = check_cables(asm, only=[back])
    assert not res.ok
    assert any(d.startswith("cable test_back") and "jetson_agx_orin" in d for d in res.details), res.details[:4]
    tight = path_of(dataclasses.replace(r, radius_mm=k.min_bend_radius_mm / 2), k)
    assert any(f"needs at least {k.min_bend_radius_mm:g} mm" in s for s in tight.problems), tight.problems
    xf = p[1][0] + k.min_bend_radius_mm
    short = dataclasses.replace(r, points=(p[0], p[1], (xf, *p[2][1:]), (xf, *p[3][1:]), p[4]))
    assert any("segment 2" in s and "too short" in s for s in path_of(short, k).problems)


@pytest.mark.slow
def test_the_jumper_wires_are_bought_from_the_routes_and_drawn_in_the_controls_step(asm):
    """The BOM's jumper_wires line counts one piece per button lead route, at the stock length the longest needs
    (no typed-in 8), and the guide's controls step lays those routes (its cable picture draws them)."""
    from docs.guide.steps import load_guide
    bom = _bought_from_routes(asm, "jumper_wires", BUTTON_LEADS)
    step = next(s for s in load_guide(asm, bom).steps if s.id == "controls")
    assert {c["route"] for c in step.cables} >= set(BUTTON_LEADS)
