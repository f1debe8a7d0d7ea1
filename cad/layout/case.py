"""The case: its interior from the parts it holds, the horizontal split plane just under the ZED X,
the lugs outside the walls that carry the split's screws, the Orin's port window in the rear wall and
the vent slots. Rig frame, mm."""
from __future__ import annotations

import math
from dataclasses import dataclass

from platform_tools.rig import Rig

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


def place_shell(rig: Rig, fits: Fits, cameras: Cameras, fans: dict[str, Fan], compute: Compute,
                floor_z: float) -> Shell:
    """The interior just holds the cameras, heat sinks, fans and the computer; the split sits a
    clearance under the ZED X; the lid is tall enough for the side handles' pads."""
    e = rig.desc.enclosure
    clear, gap, wall = fits.clear, fits.gap, fits.wall
    zed_box = cameras.zed_box
    half_in = max([abs(zed_box.lo[1]) + clear, abs(zed_box.hi[1]) + clear, compute.orin.size[1] / 2 + clear]
                  + [max(abs(f.box.lo[1]), abs(f.box.hi[1])) + gap for f in fans.values()]
                  + [max(abs(t.heat_sink.lo[1]), abs(t.heat_sink.hi[1])) + gap for t in cameras.thermal.values()])
    split_z = zed_box.lo[2] - clear
    top_in = max(zed_box.hi[2], compute.card_box.hi[2]) + clear
    if e.handles.sides:  # the lid's side walls carry the side handles' feet and pads
        top_in = max(top_in, split_z + e.handles.grip_diameter_mm + 2 * PAD_MARGIN_MM + 2 * wall + LID_SIDE_MARGIN_MM)
    front_out = zed_box.hi[0]
    interior = Bounds((compute.orin_box.lo[0] - clear, -half_in, floor_z), (front_out - wall, half_in, top_in))
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


def port_cutout(fits: Fits, shell: Shell, compute: Compute) -> Bounds:
    """The rear wall's window onto the Orin's ports: a notch open at the split, so the tray prints
    without bridging it (a closed window is a ~110 mm bridge, beyond any printer's ``max_bridge_mm``);
    the lid's rear wall closes it from above."""
    o, b, clear = shell.outer, compute.orin_box, fits.clear
    top = max(b.lo[2] + compute.orin.port_panel_height_mm + clear, shell.split_z + HOLE_LEAD_MM)
    return Bounds((o.lo[0] - PORT_CUT_OVERRUN_MM, b.lo[1] - clear, b.lo[2] - clear),
                  (shell.interior.lo[0] + PORT_CUT_OVERRUN_MM, b.hi[1] + clear, top))


def place_vents(rig: Rig, c: Constants, fits: Fits, shell: Shell, lugs, cameras: Cameras, fans: dict[str, Fan],
                compute: Compute, converter_box: Bounds) -> tuple[Bounds, ...]:
    """Vertical slots in the lower side walls beside the fans and the computer, clear of lugs and the
    converter, and exhaust slots in the front wall ahead of each fin bank, outside the window cone."""
    v = rig.desc.enclosure.vents
    o, i, split_z, wall, run = shell.outer, shell.interior, shell.split_z, fits.wall, VENT_CUT_OVERRUN_MM
    z_mid = (i.lo[2] + split_z) / 2
    zlen = min(v.slot_length_mm, split_z - i.lo[2] - 2 * wall)
    pitch = v.slot_width_mm + max(fits.min_wall * 2, v.slot_width_mm)
    keep_out: dict[float, list[tuple[float, float]]] = {1.0: [], -1.0: []}
    for x, s in lugs:
        keep_out[s].append((x - c.lug_width_mm / 2 - wall, x + c.lug_width_mm / 2 + wall))
    keep_out[-1.0].append((converter_box.lo[0] - wall, converter_box.hi[0] + wall))
    zones = [(f.box.lo[0], f.box.hi[0]) for f in fans.values()] + [(compute.orin_box.lo[0], compute.orin_box.hi[0])]
    vents = []
    for s in (1.0, -1.0):
        x = i.lo[0] + wall + v.slot_width_mm
        while x < i.hi[0] - wall - v.slot_width_mm:
            x0, x1 = x - v.slot_width_mm / 2, x + v.slot_width_mm / 2
            if any(a <= x0 and x1 <= bb for a, bb in zones) and not any(x1 > a and x0 < bb for a, bb in keep_out[s]):
                y0, y1 = (i.hi[1] - run, o.hi[1] + run) if s > 0 else (o.lo[1] - run, i.lo[1] + run)
                vents.append(Bounds((x0, y0, z_mid - zlen / 2), (x1, y1, z_mid + zlen / 2)))
            x += pitch
    half = fov_half_angles_deg(rig)["thermal"][0] + c.fov_margin_deg
    for t in cameras.thermal.values():
        cam = t.pose.t
        r_win = (o.hi[0] - cam[0]) * math.tan(math.radians(half))
        lens_r = cameras.lens.diameter_mm / 2 + fits.clear
        r_win = max(r_win, lens_r)
        y, last, outermost = t.fin_bank.centre[1], None, False
        # the slots stay on the front's flat, a minimum wall short of where its corner radius begins (a slot
        # into the radius left a 0.47 mm sliver between its side and the rounded face: the wall check)
        y_max = min(o.hi[1] - rig.desc.enclosure.corner_radius_mm, i.hi[1]) - fits.min_wall - v.slot_width_mm / 2
        while not outermost:
            if abs(y) >= y_max:
                y, outermost = t.sign * y_max, True
            clear_of_last = last is None or abs(y - last) >= pitch
            if abs(y - cam[1]) - v.slot_width_mm / 2 >= r_win + fits.min_wall and clear_of_last:
                zl = min(v.slot_length_mm, t.fin_bank.size[2])
                vents.append(Bounds((i.hi[0] - run, y - v.slot_width_mm / 2, t.fin_bank.centre[2] - zl / 2),
                                    (o.hi[0] + run, y + v.slot_width_mm / 2, t.fin_bank.centre[2] + zl / 2)))
                last = y
            y += t.sign * pitch
    return tuple(vents)
