"""The case: its interior from the parts it holds, the horizontal split plane just under the ZED X,
the lugs outside the walls that carry the split's screws, the Orin's port window in the rear wall and
the vent slots. Rig frame, mm."""
from __future__ import annotations

import math
from dataclasses import dataclass

from platform_tools.rig import Rig

from cad.bought.base import part_of_kind
from cad.bought.cables import cable_table
from cad.bought.electronics import BoxPart
from cad.bought.fan import BlowerFan
from cad.geom import Bounds, Vec3

from .cameras import Cameras, fov_half_angles_deg
from .compute import Compute
from .constants import HOLE_LEAD_MM, PAD_MARGIN_MM, Constants
from .cooling import Fan
from .fits import Fits

#: room above the side handles' pads in the lid's side walls
LID_SIDE_MARGIN_MM = 2.0
#: the lugs stand this far in from where the case's corner radius ends
LUG_CORNER_MARGIN_MM = 2.0
#: a lug reaches this far into the wall it stands on (so the two fuse)
LUG_WALL_OVERLAP_MM = 0.5
#: the lug's screw sits this far outboard of the middle of the lug's protrusion
LUG_SCREW_OUTBOARD_MM = 0.25
#: the port window's cutting box runs this far past both faces of the rear wall
PORT_CUT_OVERRUN_MM = 1.0
#: a vent slot's cutting box runs this far past both faces of its wall
VENT_CUT_OVERRUN_MM = 0.5
#: the lid's front ledge is left this much under half the printer's longest bridge
LEDGE_MARGIN_MM = 2.0
#: the roof's intake slots for the devkit's fan reach this far beyond the devkit's side (the antennas
#: stand 14 mm beyond it, cad/layout/controls.py)
ROOF_BEYOND_ORIN_MM = 8.0
#: a blower draws its intake through the openings whose centres lie within this many inlet diameters of its
#: inlet's axis, in the wall the inlet faces (cad/airflow.py's ``blower_<side>_intake``): a plain suction
#: opening's centre-line speed falls to about 7 % of its face speed one diameter out (Dalla Valle's
#: V = Q / (10 x^2 + A), the industrial-ventilation rule of thumb), so air through a slot further out is
#: the case's air, not the fan's. A rule of thumb, not a measurement
INTAKE_REACH_DIAMETERS = 1.0


@dataclass(frozen=True)
class Shell:
    interior: Bounds
    outer: Bounds               # the interior grown by the wall; the front is flush with the ZED X
    split_z: float              # the split plane between the lower tray and the lid


@dataclass(frozen=True)
class Case:
    interior: Bounds
    outer: Bounds
    split_z: float
    lugs: tuple[tuple[float, float], ...]   # (x, side sign): one lug pair per entry
    port_cutout: Bounds         # the Orin's port window in the rear wall
    vents: tuple[Bounds, ...]   # cutting boxes of the vent slots


def rear_plug_room_mm(fits: Fits) -> float:
    """How far the rear wall's inner face stands behind the Orin's port face: the deepest right-angle plug
    of the cable table (``plugs`` of ``cad/bought/cables.yaml``: every one goes into a rear port) plus the
    component clearance, never less than the clearance alone.

    Why the whole rear wall and not a pocket over the port window (docs/cad.md, "The Orin's rear ports"): a
    pocket closed above in the tray has a roof over the plugs, and the Orin goes into the tray from above
    with its plugs in (they would hit the roof); a pocket open above needs the lid over it, and the lid
    prints on its rear face, which must stay one flat face. Moved back whole, the wall keeps the port window
    (a notch open at the split, the external access), the lid stays flat on the bed, and nothing inside
    moves."""
    plugs = cable_table().plugs.values()
    return max([fits.clear] + [p.depth_mm + fits.clear for p in plugs])


def place_shell(rig: Rig, fits: Fits, cameras: Cameras, fans: dict[str, Fan], compute: Compute,
                floor_z: float) -> Shell:
    """The interior just holds the cameras, heat sinks, fans and the computer with the plugs in its rear
    ports (:func:`rear_plug_room_mm`); the split sits a clearance under the ZED X; the lid is tall enough
    for the side handles' pads."""
    e = rig.desc.enclosure
    clear, gap, wall = fits.clear, fits.gap, fits.wall
    zed_box = cameras.zed_box
    # the DC-DC converter stands on its base against the right wall beside the devkit (cad/layout/power.py):
    # its height off the wall plus a clearance to the devkit's side
    conv = BoxPart.from_rig(rig, part_of_kind(rig, "converter"))
    half_in = max([abs(zed_box.lo[1]) + clear, abs(zed_box.hi[1]) + clear, compute.orin.size[1] / 2 + clear,
                   abs(compute.orin_box.lo[1]) + clear + conv.size[2]]
                  + [max(abs(f.box.lo[1]), abs(f.box.hi[1])) + gap for f in fans.values()]
                  + [max(abs(t.heat_sink.lo[1]), abs(t.heat_sink.hi[1])) + gap for t in cameras.thermal.values()])
    split_z = zed_box.lo[2] - clear
    top_in = max(zed_box.hi[2], compute.card_box.hi[2]) + clear
    if e.handles.sides:  # the lid's side walls carry the side handles' feet and pads
        top_in = max(top_in, split_z + e.handles.grip_diameter_mm + 2 * PAD_MARGIN_MM + 2 * wall + LID_SIDE_MARGIN_MM)
    front_out = zed_box.hi[0]
    rear_in = compute.orin_box.lo[0] - rear_plug_room_mm(fits)   # room for the right-angle plugs in its ports
    interior = Bounds((rear_in, -half_in, floor_z), (front_out - wall, half_in, top_in))
    grown = interior.grown(wall)
    return Shell(interior=interior, outer=Bounds(grown.lo, (front_out, grown.hi[1], grown.hi[2])), split_z=split_z)


def place_lugs(rig: Rig, c: Constants, shell: Shell) -> tuple[tuple[float, float], ...]:
    """Three lug pairs per side: near the front, in the middle and near the rear."""
    o = shell.outer
    w, r = c.lug_width_mm, rig.desc.enclosure.corner_radius_mm
    xs = [o.hi[0] - w / 2 - r - LUG_CORNER_MARGIN_MM,
          (o.lo[0] + o.hi[0]) / 2,
          o.lo[0] + w / 2 + r + LUG_CORNER_MARGIN_MM]
    return tuple((x, s) for x in xs for s in (1.0, -1.0))


def lug_bounds(case: Case | Shell, c: Constants, fits: Fits, x: float, s: float) -> Bounds:
    """The lug pair's footprint, both halves and their gussets (for clash tests with pads)."""
    o = case.outer
    p = c.lug_protrusion_mm
    y0, y1 = (o.hi[1] - LUG_WALL_OVERLAP_MM, o.hi[1] + p) if s > 0 else (o.lo[1] - p, o.lo[1] + LUG_WALL_OVERLAP_MM)
    return Bounds((x - c.lug_width_mm / 2, y0, case.split_z - fits.insert_plate_mm - p),
                  (x + c.lug_width_mm / 2, y1, case.split_z + c.lid_lug_mm + p))


def lug_screw_point(case: Case, c: Constants, x: float, s: float) -> Vec3:
    """Where the lug's screw crosses the split plane."""
    o = case.outer
    half = c.lug_protrusion_mm / 2
    y = o.hi[1] + half + LUG_SCREW_OUTBOARD_MM if s > 0 else o.lo[1] - half - LUG_SCREW_OUTBOARD_MM
    return (x, y, case.split_z)


def lug_spot_face(case: Case, c: Constants, x: float, s: float) -> Bounds:
    """The flat spot face the lid lug's screw head sits on: the lug's gusset cut away above the head,
    from the screw's axis outwards (a counterbore through the 45 deg gusset left a knife-edge sliver
    on its outboard side, 0.06 mm thick at the edge; the wall check found it)."""
    _, y, z = lug_screw_point(case, c, x, s)
    o, p, top = case.outer, c.lug_protrusion_mm, case.split_z + c.lid_lug_mm
    y0, y1 = (y, o.hi[1] + p + HOLE_LEAD_MM) if s > 0 else (o.lo[1] - p - HOLE_LEAD_MM, y)
    return Bounds((x - c.lug_width_mm / 2 - HOLE_LEAD_MM, y0, top), (x + c.lug_width_mm / 2 + HOLE_LEAD_MM, y1, top + p + HOLE_LEAD_MM))


def front_ledge_chamfer(rig: Rig, fits: Fits, shell: Shell, cameras: Cameras) -> float:
    """The 45 deg chamfer under the roof behind the lid's front wall: the lid prints on its rear face,
    so the front wall above the ZED X's notch is a ledge hanging from the roof, as long as the roof is
    above the notch (20.5 mm once the capture card stood clear of the devkit's fan: a 41 mm span, the
    overhang check). The chamfer shortens it to ``LEDGE_MARGIN_MM`` under half the printer's
    ``max_bridge_mm``; 0 when it is short enough."""
    notch_top = cameras.zed_box.hi[2] + fits.clear
    ledge = shell.interior.hi[2] - notch_top
    return max(0.0, ledge - (rig.desc.printing.printer.max_bridge_mm / 2 - LEDGE_MARGIN_MM))


def port_cutout(fits: Fits, shell: Shell, compute: Compute) -> Bounds:
    """The rear wall's window onto the Orin's ports: a notch open at the split, so the tray prints
    without bridging it (a closed window is a ~110 mm bridge, beyond any printer's ``max_bridge_mm``);
    the lid's rear wall closes it from above."""
    o, b, clear = shell.outer, compute.orin_box, fits.clear
    top = max(b.lo[2] + compute.orin.port_panel_height_mm + clear, shell.split_z + HOLE_LEAD_MM)
    return Bounds((o.lo[0] - PORT_CUT_OVERRUN_MM, b.lo[1] - clear, b.lo[2] - clear),
                  (shell.interior.lo[0] + PORT_CUT_OVERRUN_MM, b.hi[1] + clear, top))


def place_vents(rig: Rig, c: Constants, fits: Fits, shell: Shell, lugs, cameras: Cameras, fans: dict[str, Fan],
                compute: Compute, converter_box: Bounds, controls: tuple[Bounds, ...] = ()) -> tuple[Bounds, ...]:
    """Every vent slot (cad/airflow.py checks each air path's free area against its fan):

    - the blowers' intakes: vertical slots in the tray's side walls, floor to split, round each fan's inlet
      (which faces its side wall), within :func:`intake_reach_mm` of its axis;
    - the devkit's exhaust: vertical slots in the tray's side walls beside it, floor to split, and
      horizontal ones in the lid's side walls between the side handle's pads (its heat sink blows out
      of its +-y faces, an estimate: ``parts.jetson_agx_orin.dims``);
    - the devkit's intake: slots along x in the roof beside the capture card, over the devkit's fan;
    - each blower's exhaust: slots in the front wall beside the Boson's window, floor to split, and
      vertical slots in the side wall beside the fin bank, until the free area reaches
      ``min_area_ratio`` x the fan's outlet.

    No slot is wider than ``slot_width_mm`` or longer than ``slot_length_mm``: a longer run is
    ``segments`` with a two-minimum-wall rib between. No slot comes within a wall of a control's box in the
    lid's side walls (``controls``: the record button's; its hole beside a slot left a 0.14 mm sliver).

    Every slot in the lid runs along x, the lid's print direction (it prints on its rear face), so its
    top in the print is a ``slot_width_mm`` bridge; every slot in the tray is vertical for the same reason."""
    v = rig.desc.enclosure.vents
    pitch = v.slot_width_mm + max(fits.min_wall * 2, v.slot_width_mm)
    keep_out: dict[float, list[tuple[float, float]]] = {1.0: [], -1.0: []}
    for x, s in lugs:
        keep_out[s].append((x - c.lug_width_mm / 2 - fits.wall, x + c.lug_width_mm / 2 + fits.wall))
    keep_out[-1.0].append((converter_box.lo[0] - fits.wall, converter_box.hi[0] + fits.wall))
    vents = _side_slots(rig, fits, shell, pitch, keep_out, fans, compute)
    keep = [b.grown(fits.wall) for b in controls]
    vents += [v for v in _lid_side_slots(rig, c, fits, shell, pitch, compute) if not any(v.overlaps(k) for k in keep)]
    vents += _roof_slots(rig, fits, shell, pitch, compute)
    for f in fans.values():
        vents += _blower_exhaust(rig, c, fits, shell, pitch, lugs, converter_box, cameras, f)
    return tuple(vents)


def segments(lo: float, hi: float, max_len: float, rib: float) -> list[tuple[float, float]]:
    """[lo, hi] split into the fewest equal segments of at most ``max_len`` (``slot_length_mm``: no slot
    is longer) with a ``rib`` between each two."""
    n = max(1, math.ceil((hi - lo + rib) / (max_len + rib) - 1e-9))
    seg = (hi - lo - (n - 1) * rib) / n
    return [(lo + k * (seg + rib), lo + k * (seg + rib) + seg) for k in range(n)]


def intake_reach_mm(rig: Rig) -> float:
    """How far from a blower's inlet axis an opening still feeds it: ``INTAKE_REACH_DIAMETERS`` x the
    fan part's inlet diameter (``parts.<fan>.dims.inlet_diameter_mm``)."""
    return INTAKE_REACH_DIAMETERS * BlowerFan.from_rig(rig, part_of_kind(rig, "fan")).inlet_diameter_mm


def _side_slots(rig: Rig, fits: Fits, shell: Shell, pitch: float, keep_out, fans: dict[str, Fan],
                compute: Compute) -> list[Bounds]:
    """Vertical slots in the tray's side walls, floor to split in ``segments``, clear of the lugs and the
    converter: beside the devkit (its exhaust), and round each fan's inlet (its intake: the inlet faces its
    side wall), columns from the fan's outlet face backwards (ahead of it the wall is the exhaust's), each
    segment whose centre is within :func:`intake_reach_mm` of the inlet's axis."""
    v = rig.desc.enclosure.vents
    o, i, split_z, wall, run = shell.outer, shell.interior, shell.split_z, fits.wall, VENT_CUT_OVERRUN_MM
    full = segments(i.lo[2] + wall, split_z - wall, v.slot_length_mm, 2 * fits.min_wall)
    b, w = compute.orin_box, v.slot_width_mm
    vents = []
    for s in (1.0, -1.0):
        cols = []   # (x, z segments)
        x = i.lo[0] + wall + w
        while x < i.hi[0] - wall - w:
            if b.lo[0] <= x - w / 2 and x + w / 2 <= b.hi[0]:
                cols.append((x, full))
            x += pitch
        for f in (f for f in fans.values() if f.sign == s):
            cols += _intake_columns(f, intake_reach_mm(rig), full, pitch, w, [c for c, _ in cols])
        y0, y1 = (i.hi[1] - run, o.hi[1] + run) if s > 0 else (o.lo[1] - run, i.lo[1] + run)
        for x, zs in cols:
            x0, x1 = x - w / 2, x + w / 2
            if not any(x1 > a and x0 < bb for a, bb in keep_out[s]):
                vents += [Bounds((x0, y0, za), (x1, y1, zb)) for za, zb in zs]
    return vents


def _intake_columns(f: Fan, reach_mm: float, full: list[tuple[float, float]], pitch: float, width: float,
                    taken: list[float]) -> list[tuple[float, list[tuple[float, float]]]]:
    """The slot columns round one fan's inlet: at ``pitch`` from its outlet face backwards while within
    ``reach_mm`` of its axis (x), each with the segments of ``full`` whose centre is within ``reach_mm`` of the
    inlet's centre (the fan box's, in x and z), none closer than a pitch to a column ``taken``: [(x, segments)]."""
    cx, cz = f.box.centre[0], f.box.centre[2]
    out, x = [], f.box.hi[0] - width / 2
    while x >= cx - reach_mm:
        zs = [(za, zb) for za, zb in full if math.hypot(x - cx, (za + zb) / 2 - cz) <= reach_mm]
        if zs and all(abs(x - c) >= pitch - 1e-9 for c in taken):
            out.append((x, zs))
        x -= pitch
    return out


def side_pad_free_x(rig: Rig, c: Constants, shell: Shell) -> tuple[float, float]:
    """The x range of the lid's side walls between a side handle's two foot pads, a wall clear of them
    (the pads' extent as cad/layout/handles.py places them: feet at the grip's ends, each a post and
    its flange wide, grown by ``PAD_MARGIN_MM``)."""
    h = rig.desc.enclosure.handles
    x_mid = (shell.outer.lo[0] + shell.outer.hi[0]) / 2
    if not h.sides:
        return shell.interior.lo[0], shell.interior.hi[0]
    half = h.grip_length_mm / 2 - c.handle_post_width_mm - c.handle_flange_mm - PAD_MARGIN_MM - rig.desc.enclosure.wall_mm
    return x_mid - half, x_mid + half


def _lid_side_slots(rig: Rig, c: Constants, fits: Fits, shell: Shell, pitch: float, compute: Compute) -> list[Bounds]:
    """Slots along x in the lid's side walls beside the devkit (its exhaust), between the side handle's
    pads and above the split's lugs and their gussets."""
    v = rig.desc.enclosure.vents
    o, i, wall, run = shell.outer, shell.interior, fits.wall, VENT_CUT_OVERRUN_MM
    lo, hi = side_pad_free_x(rig, c, shell)
    x0, x1 = max(lo, compute.orin_box.lo[0]), min(hi, compute.orin_box.hi[0])
    if x1 - x0 < v.slot_width_mm:
        return []
    z = shell.split_z + c.lid_lug_mm + c.lug_protrusion_mm + wall + v.slot_width_mm / 2
    vents = []
    while z + v.slot_width_mm / 2 <= i.hi[2] - wall:
        for s in (1.0, -1.0):
            y0, y1 = (i.hi[1] - run, o.hi[1] + run) if s > 0 else (o.lo[1] - run, i.lo[1] + run)
            vents += [Bounds((xa, y0, z - v.slot_width_mm / 2), (xb, y1, z + v.slot_width_mm / 2))
                      for xa, xb in segments(x0, x1, v.slot_length_mm, 2 * fits.min_wall)]
        z += pitch
    return vents


def _roof_slots(rig: Rig, fits: Fits, shell: Shell, pitch: float, compute: Compute) -> list[Bounds]:
    """Slots along x in the roof over the devkit, beside the capture card (whose edges the devkit's fan
    draws its air round): from the card's edge to ``ROOF_BEYOND_ORIN_MM`` past the devkit's side (the
    antennas stand further out), in segments of at most ``slot_length_mm`` with a two-minimum-wall rib
    between."""
    v = rig.desc.enclosure.vents
    i, o, b, run = shell.interior, shell.outer, compute.orin_box, VENT_CUT_OVERRUN_MM
    y_in = compute.card_box.hi[1] + fits.clear + v.slot_width_mm / 2
    y_out = b.hi[1] + fits.clear + ROOF_BEYOND_ORIN_MM - v.slot_width_mm / 2
    # the ribs across the slots only tie the roof's strips between two rows: two minimum walls
    segs = segments(max(b.lo[0], i.lo[0] + fits.wall), b.hi[0], v.slot_length_mm, 2 * fits.min_wall)
    vents = []
    y = y_in
    while y <= y_out + 1e-9:
        for s in (1.0, -1.0):
            vents += [Bounds((xa, s * y - v.slot_width_mm / 2, i.hi[2] - run), (xb, s * y + v.slot_width_mm / 2, o.hi[2] + run))
                      for xa, xb in segs]
        y += pitch
    return vents


def _blower_exhaust(rig: Rig, c: Constants, fits: Fits, shell: Shell, pitch: float, lugs, converter_box: Bounds,
                    cameras: Cameras, f: Fan) -> list[Bounds]:
    """One blower's exhaust, sized to its outlet: the front wall's slot outboard of the Boson's window
    (at the outer edge of the front's flat there, floor to split in ``segments``), then vertical slots in the
    side wall beside the fin bank, ahead of the fan, until the free area reaches ``min_area_ratio`` x
    the outlet's area (``BlowerFan.outlet``)."""
    v = rig.desc.enclosure.vents
    o, i, split_z, wall, run = shell.outer, shell.interior, shell.split_z, fits.wall, VENT_CUT_OVERRUN_MM
    t = next(t for t in cameras.thermal.values() if t.sign == f.sign)
    need = v.min_area_ratio * f.outlet_area_mm2
    half = fov_half_angles_deg(rig)["thermal"][0] + c.fov_margin_deg
    r_win = max((o.hi[0] - t.pose.t[0]) * math.tan(math.radians(half)), cameras.lens.diameter_mm / 2 + fits.clear)
    # the slot stays on the front's flat, a minimum wall short of where its corner radius begins (a slot
    # into the radius left a 0.47 mm sliver between its side and the rounded face: the wall check)
    y_out = min(o.hi[1] - rig.desc.enclosure.corner_radius_mm, i.hi[1]) - fits.min_wall
    y_in = abs(t.pose.t[1]) + r_win + fits.min_wall
    z0, z1 = i.lo[2] + wall, split_z - wall
    vents, have = [], 0.0
    if y_out - y_in >= v.slot_width_mm:
        ya, yb = sorted((f.sign * (y_out - v.slot_width_mm), f.sign * y_out))
        for za, zb in segments(z0, z1, v.slot_length_mm, 2 * fits.min_wall):
            vents.append(Bounds((i.hi[0] - run, ya, za), (o.hi[0] + run, yb, zb)))
            have += v.slot_width_mm * (zb - za)
    # beside the fin bank (its fins are open outboard), from its front backwards, a wall clear of the
    # lugs (which stand higher up the wall than the fin bank: their boxes, not just their x range)
    y0, y1 = (i.hi[1] - run, o.hi[1] + run) if f.sign > 0 else (o.lo[1] - run, i.lo[1] + run)
    za, zb = t.fin_bank.lo[2], t.fin_bank.hi[2]
    blocked = [lug_bounds(shell, c, fits, x, s).grown(wall) for x, s in lugs if s == f.sign] + [converter_box.grown(wall)]
    x = t.fin_bank.hi[0] - v.slot_width_mm / 2
    while have < need - 1e-9 and x - v.slot_width_mm / 2 >= t.fin_bank.lo[0] - 1e-9:
        slot = Bounds((x - v.slot_width_mm / 2, y0, za), (x + v.slot_width_mm / 2, y1, zb))
        # a lug above: the slot stops a wall under it
        top = min([b.lo[2] for b in blocked if slot.overlaps(b) and b.lo[2] > za + v.slot_width_mm] + [zb])
        slot = Bounds(slot.lo, (slot.hi[0], slot.hi[1], top))
        if not any(slot.overlaps(b) for b in blocked):
            vents.append(slot)
            have += v.slot_width_mm * (top - za)
        x -= pitch
    return vents
