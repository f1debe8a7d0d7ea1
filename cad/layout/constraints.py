"""What makes the design impossible, found before any geometry is built: the rig loader cannot know
that a camera runs into another or that a handle does not fit the case. Every problem names the rig
key (or design constant) to change, so an impossible value never reaches OpenCascade."""
from __future__ import annotations

import math
from typing import Callable

from platform_tools.rig import Rig

from cad.bought.base import part_of_kind

from .case import lug_bounds
from .constants import PAD_MARGIN_MM, C, Constants
from .errors import DesignError, DesignProblem     # noqa: F401 - raised here; callers import them from here
from .rig_layout import Layout, build_layout

#: the least post a handle needs between its foot and its grip
MIN_POST_MM = 2.0



def design_problems(rig: Rig, c: Constants = C) -> list[DesignProblem]:
    """What makes the design impossible: first the rig values alone, then the layout made from them."""
    problems = list(input_problems(rig))
    if problems:
        return problems
    try:
        lay = build_layout(rig, c)
    except ValueError as exc:  # a stock screw or a box that cannot be made from these values
        return [DesignProblem("enclosure", f"the layout cannot be made from these values: {exc}")]
    return list(layout_problems(lay))


def input_problems(rig: Rig):
    """Rig values that cannot make a layout at all."""
    d = rig.desc
    e = d.enclosure
    p = d.printing.printer
    min_wall = p.nozzle_mm * p.min_wall_nozzles
    if e.heat_sink.fin_count > 1:
        hs = e.heat_sink
        height = rig.part(d.sensors.thermal.part).envelope_mm.z.value + 2 * hs.wall_mm
        gap = (height - hs.fin_count * hs.fin_thickness_mm) / (hs.fin_count - 1)
        if gap < hs.fin_thickness_mm:
            yield DesignProblem("enclosure.heat_sink.fin_count",
                                f"{hs.fin_count} fins of {hs.fin_thickness_mm:g} mm on a {height:g} mm tall heat sink "
                                f"leave {gap:.2f} mm between fins; expected at least {hs.fin_thickness_mm:g} mm")
    if e.vents.slot_width_mm < min_wall:
        yield DesignProblem("enclosure.vents.slot_width_mm", f"{e.vents.slot_width_mm:g} mm is narrower than a wall")
    if e.corner_radius_mm >= e.handles.grip_diameter_mm:
        yield DesignProblem("enclosure.corner_radius_mm", "is larger than the handle grip; expected a few mm")
    orin = part_of_kind(rig, "computer")
    fan, hub = rig.dim(orin, "fan_diameter_mm"), rig.dim(orin, "fan_hub_diameter_mm")
    if not 0 <= hub < fan:   # the devkit's fan would have no free ring: its intake would need nothing (cad/airflow.py)
        yield DesignProblem(f"parts.{orin}.dims.fan_hub_diameter_mm",
                            f"{hub:g} mm, expected 0 to under fan_diameter_mm ({fan:g} mm): the fan would have no free ring")
    zed = d.sensors.zed_x.part
    zw = rig.part(zed).envelope_mm.y.value
    zb = rig.dim(zed, "baseline_mm")
    win = rig.dim(zed, "lens_window_diameter_mm")
    if zb + win > zw:
        yield DesignProblem(f"parts.{zed}.dims.baseline_mm",
                            f"{zb:g} mm baseline with {win:g} mm lens windows does not fit a {zw:g} mm wide camera "
                            f"(expected baseline <= {zw - win:g} mm)")


def layout_problems(lay: Layout):
    """A layout that can be computed but not built: parts in each other, handles that do not fit,
    a case too big for the printer, too little vent area."""
    yield from _camera_problems(lay)
    yield from _handle_problems(lay)
    yield from _print_and_vent_problems(lay)


def _camera_problems(lay: Layout):
    rig, cams, mounts, fits, case = lay.rig, lay.cameras, lay.mounts, lay.fits, lay.case
    t = rig.desc.sensors.thermal
    gap = rig.desc.enclosure.heat_sink_gap_mm
    # the thermal pair must sit below the ZED X with room for its heat sinks and the ZED shelf
    hs_top = max(s.heat_sink.hi[2] for s in cams.thermal.values())
    shelf = mounts.zed_shelf
    if hs_top > shelf.lo[2] - gap:
        yield DesignProblem("sensors.thermal.pose.xyz_mm",
                            f"the Boson heat sinks reach z = {hs_top:.1f} mm, into the ZED X and its mount (shelf "
                            f"underside at {shelf.lo[2]:.1f} mm); move the pair down by at least "
                            f"{hs_top - shelf.lo[2] + gap:.1f} mm")
    inner_edge = min(abs(s.heat_sink.lo[1]) if s.sign > 0 else abs(s.heat_sink.hi[1]) for s in cams.thermal.values())
    legs = mounts.zed_legs
    leg_edge = max(abs(b.lo[1]) for b in legs) if legs else 0
    if any(legs[0].overlaps(s.heat_sink) or legs[1].overlaps(s.heat_sink) for s in cams.thermal.values()):
        yield DesignProblem("sensors.thermal.baseline_mm",
                            f"{t.baseline_mm:g} mm leaves the inner heat sink faces at |y| = {inner_edge:.1f} mm, "
                            f"inside the ZED X mount legs (|y| <= {leg_edge:.1f} mm)")
    front_in = case.outer.hi[0] - fits.wall
    for s in cams.thermal.values():
        lens_front = s.pose.t[0] + cams.lens.front_mm
        if lens_front > front_in + 1e-6:
            yield DesignProblem("sensors.thermal.pose.xyz_mm",
                                f"the {s.side} Boson lens front (x = {lens_front:.1f} mm) is ahead of the front wall's "
                                f"inner face (x = {front_in:.1f} mm, set by the ZED X front); "
                                f"move the pair back")
        if s.heat_sink.hi[0] + fits.gap > front_in:
            yield DesignProblem("sensors.thermal.pose.xyz_mm", f"the {s.side} heat sink is within the gap of the front wall")
    need = fits.insert.outer_diameter_mm + 2 * (fits.min_wall + fits.gap)   # the bar's floor screws sit between
    if 2 * inner_edge < need:
        yield DesignProblem("sensors.thermal.baseline_mm",
                            f"{t.baseline_mm:g} mm leaves {2 * inner_edge:.1f} mm between the two heat sinks; the thermal "
                            f"bar's floor screw inserts need {need:.1f} mm there (expected baseline >= "
                            f"{t.baseline_mm + need - 2 * inner_edge:.1f} mm)")
    if mounts.zed_foot.overlaps(mounts.thermal_bar):
        yield DesignProblem("sensors.thermal.pose.xyz_mm", "the ZED X mount's foot runs into the thermal bar")


def grip_length_ranges(lay: Layout) -> list[tuple[float, float]]:
    """The grip lengths (mm) this case takes, as closed intervals: long enough to be a grip, with both
    feet and their pads inside the case's straight length, and no foot pad on a split lug.

    A pad's y and z do not depend on the grip length, only its x does: a foot's pad is centred at
    ``x_mid +- (L/2 - post/2)``, so each pad that shares y and z with a lug forbids one open interval
    of L. What is left of ``[post width + 2 x MIN_POST_MM, the fit limit]`` is returned."""
    case, g, c = lay.case, lay.handles.geometry, lay.c
    r = lay.rig.desc.enclosure.corner_radius_mm
    x_mid = (case.outer.lo[0] + case.outer.hi[0]) / 2
    lo = 2 * g.post_width + MIN_POST_MM              # two posts and a little grip between them
    hi = case.outer.size[0] - 2 * r - 2 * g.flange - 2 * PAD_MARGIN_MM
    pad_half = g.post_width / 2 + g.flange + PAD_MARGIN_MM
    forbidden = []
    for pad in lay.handles.pads:
        s = 1.0 if pad.centre[0] > x_mid else -1.0
        for x, side in case.lugs:
            lug = lug_bounds(case, c, lay.fits, x, side)
            if not all(pad.lo[k] < lug.hi[k] and lug.lo[k] < pad.hi[k] for k in (1, 2)):
                continue
            # with u = L/2 - post/2: |x_mid + s u - x| < reach  <=>  s (x - x_mid) - reach < u < ... + reach
            reach = pad_half + c.lug_width_mm / 2
            u0, u1 = s * (x - x_mid) - reach, s * (x - x_mid) + reach
            forbidden.append((2 * u0 + g.post_width, 2 * u1 + g.post_width))
    ranges = [(lo, hi)] if hi >= lo else []
    for a, b in sorted(forbidden):
        out = []
        for r0, r1 in ranges:
            if b <= r0 or a >= r1:
                out.append((r0, r1))
                continue
            if a > r0:
                out.append((r0, a))
            if b < r1:
                out.append((b, r1))
        ranges = out
    return ranges


def _format_ranges(ranges: list[tuple[float, float]]) -> str:
    if not ranges:
        return "no grip length fits this case; make the case longer or the handle posts narrower"
    # round inwards to 0.1 mm so the value suggested really passes
    return "expected " + " or ".join(f"{math.ceil(a * 10) / 10:.1f} to {math.floor(b * 10) / 10:.1f} mm"
                                     for a, b in ranges)


def min_clearance(lay: Layout) -> float:
    """The least ``enclosure.handles.clearance_mm`` (mm) that leaves a post between a foot and the grip."""
    return lay.handles.geometry.foot + MIN_POST_MM + lay.handles.pad_mm


def _has_handles(lay: Layout) -> bool:
    h = lay.rig.desc.enclosure.handles
    return bool(h.top or h.sides)


#: rig keys whose real range only the layout knows (the rig loader checks their type and sign only, e.g.
#: "> 0"): key -> the layout's "expected ..." for it, or None when this layout sets it no limit. Neither
#: depends on the key's own value, so a layout made without the refused value gives the real range.
LAYOUT_LIMITS: dict[str, Callable[[Layout], str | None]] = {
    "enclosure.handles.grip_length_mm":
        lambda lay: _format_ranges(grip_length_ranges(lay)) if _has_handles(lay) else None,
    "enclosure.handles.clearance_mm":
        lambda lay: f"expected >= {min_clearance(lay):g} mm" if _has_handles(lay) else None,
}


def _handle_problems(lay: Layout):
    rig, case = lay.rig, lay.case
    h = rig.desc.enclosure.handles
    g = lay.handles.geometry
    length = case.outer.size[0]
    if h.top or h.sides:
        ranges = grip_length_ranges(lay)
        if not any(a - 1e-9 <= h.grip_length_mm <= b + 1e-9 for a, b in ranges):
            foot_len = g.grip_length + 2 * g.flange + 2 * PAD_MARGIN_MM    # both feet with their pads
            clashes = sorted({round(x, 1) for pad in lay.handles.pads for x, s in case.lugs
                              if pad.overlaps(lug_bounds(case, lay.c, lay.fits, x, s))})
            why = (f"its feet ({foot_len:g} mm) do not fit the {length:.1f} mm long case" if not clashes else
                   "its foot pads run into the case's split lugs at x = " + ", ".join(f"{x:g}" for x in clashes) + " mm")
            yield DesignProblem("enclosure.handles.grip_length_mm",
                                f"got {h.grip_length_mm:g} mm; {why}; {_format_ranges(ranges)}")
        if g.post_height < g.foot + MIN_POST_MM:
            yield DesignProblem("enclosure.handles.clearance_mm",
                                f"{h.clearance_mm:g} mm leaves no post between the foot and the grip; expected >= "
                                f"{min_clearance(lay):g} mm")
    pad_h = h.grip_diameter_mm + 2 * PAD_MARGIN_MM    # a side handle's pad, up the lid's wall
    if h.sides and pad_h > case.outer.hi[2] - case.split_z - 2 * lay.fits.wall:
        yield DesignProblem("enclosure.handles.grip_diameter_mm",
                            f"side handle feet ({pad_h:g} mm tall) do not fit the lid's "
                            f"{case.outer.hi[2] - case.split_z:.1f} mm side walls")


def _print_and_vent_problems(lay: Layout):
    rig, o, p = lay.rig, lay.case.outer, lay.c.lug_protrusion_mm
    # every printed part fits the bed (the case halves, with their lugs, are the largest)
    bed = rig.desc.printing.printer.bed_mm
    footprint = sorted([o.size[0], o.size[1] + 2 * p])
    if footprint[1] > max(bed[:2]) or footprint[0] > min(bed[:2]):
        yield DesignProblem("printing.printer.bed_mm",
                            f"the case halves ({o.size[0]:.0f} x {o.size[1] + 2 * p:.0f} mm with "
                            f"lugs) do not fit the {bed[0]:g} x {bed[1]:g} mm bed")
    # the vents must reach the configured area (checked on the geometry too)
    v = rig.desc.enclosure.vents
    vents = lay.case.vents
    need = v.min_area_ratio * 2 * lay.cooling.part.inlet_area_mm2
    have = sum(b.size[2] * (b.size[0] if b.size[1] > b.size[0] else b.size[1]) for b in vents)
    if have < need:
        yield DesignProblem("enclosure.vents.slot_length_mm",
                            f"the walls take {len(vents)} slots, {have:.0f} mm^2 open; the fans need "
                            f"{need:.0f} mm^2 (min_area_ratio {v.min_area_ratio:g}); use longer or wider slots")
