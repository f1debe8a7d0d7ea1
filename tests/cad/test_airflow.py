"""The air paths through the case (cad/airflow.py, issue 16 item 6): each path's free area against its
fan's need, on the B-rep and on the exported STL, and the clear height over the devkit's fan.

The independent paths here: meshes made by trimesh (not by OpenCascade) for the ray caster's own
test, and the exported case STL read by trimesh's reader and cast through by trimesh's ray caster,
against the check's B-rep figure."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from cad.airflow import (AGREE_ABS_MM2, AGREE_REL, Window, _wall_axis, air_paths, first_hits, stl_free_area_mm2)
from cad.geom import Bounds, placed_bounds

trimesh = pytest.importorskip("trimesh")


def _tri(*meshes) -> np.ndarray:
    return np.concatenate([m.triangles for m in meshes])


def _plate_with_slot(gap: float, length: float = 20.0, wall: float = 2.0):
    """Two trimesh boxes a ``gap`` apart in y (a slot through a wall whose normal is z), ``length`` in x."""
    a = trimesh.creation.box((length, 10.0, wall), trimesh.transformations.translation_matrix((0, -5 - gap / 2, 0)))
    b = trimesh.creation.box((length, 10.0, wall), trimesh.transformations.translation_matrix((0, 5 + gap / 2, 0)))
    return a, b


def _slot_window(gap: float, length: float = 20.0, wall: float = 2.0, step: float = 0.25) -> Window:
    return Window(Bounds((-length / 2 + step, -gap / 2 - step, -wall / 2), (length / 2 - step, gap / 2 + step, wall / 2)), 2,
                  (step, step))


def test_rays_through_a_slot_in_a_trimesh_plate_measure_its_area():
    tri = _tri(*_plate_with_slot(3.0))
    free, rays = stl_free_area_mm2(tri, (_slot_window(3.0),))
    assert free == pytest.approx(3.0 * 19.5, rel=1e-9)      # the window's length (20 - 2 x 0.25) x the slot's 3 mm
    assert rays == 78 * 14


def test_a_closed_plate_lets_nothing_through_and_a_ray_beside_it_passes():
    plate = trimesh.creation.box((20.0, 20.0, 2.0))
    tri = plate.triangles
    free, _ = stl_free_area_mm2(tri, (_slot_window(3.0),))
    assert free == 0.0
    # first_hits gives the plate's lower face for rays that meet it, inf beside it
    hits = first_hits(tri, 2, np.array([[0.0, 0.0], [15.0, 0.0], [9.9, -9.9]]), -5.0, 5.0)
    assert hits[0] == pytest.approx(-1.0) and math.isinf(hits[1]) and hits[2] == pytest.approx(-1.0)


def test_a_slot_blocked_behind_the_wall_is_seen_by_the_rays():
    a, b = _plate_with_slot(3.0)
    # a bar 1 mm wide across the slot, just above the wall: inside the rays' overrun (0.5 mm)
    bar = trimesh.creation.box((20.0, 1.0, 0.4), trimesh.transformations.translation_matrix((0, 0, 1.2)))
    free, _ = stl_free_area_mm2(_tri(a, b, bar), (_slot_window(3.0),))
    assert free == pytest.approx(2.0 * 19.5, abs=0.25 * 19.5)


def test_slots_are_assigned_to_the_wall_they_cross():
    outer = Bounds((-100, -50, -40), (10, 50, 30))
    assert _wall_axis(Bounds((9, 20, -10), (11, 23, 0)), outer) == 0
    assert _wall_axis(Bounds((-50, 49, -10), (-47, 51, 0)), outer) == 1
    assert _wall_axis(Bounds((-50, -51, -10), (-47, -49, 0)), outer) == 1
    assert _wall_axis(Bounds((-50, 20, 29), (-20, 23, 31)), outer) == 2
    assert _wall_axis(Bounds((-101, 20, 0), (-99, 23, 5)), outer) is None      # the rear wall: no path uses it


@pytest.fixture(scope="module")
def lay(rig):
    from cad.layout import layout
    return layout(rig)


PATHS = ("blower_left_intake", "blower_right_intake", "blower_left_exhaust", "blower_right_exhaust", "orin_intake",
         "orin_exhaust")


def test_every_path_has_slots_and_needs_what_its_fan_asks(lay, rig):
    paths = {p.name: p for p in air_paths(lay)}
    assert set(paths) == set(PATHS)
    ratio = rig.desc.enclosure.vents.min_area_ratio
    outlet = rig.dim("fan_3010_5v", "outlet_width_mm") * rig.dim("fan_3010_5v", "outlet_height_mm")
    assert paths["blower_left_exhaust"].need_mm2 == pytest.approx(ratio * outlet)      # 1.5 x 21 x 8.3 mm
    inlet = math.pi / 4 * rig.dim("fan_3010_5v", "inlet_diameter_mm") ** 2
    for side in ("left", "right"):
        assert paths[f"blower_{side}_intake"].need_mm2 == pytest.approx(ratio * inlet)  # 1.5 x pi/4 x 26^2
    d, hub = rig.dim("jetson_agx_orin", "fan_diameter_mm"), rig.dim("jetson_agx_orin", "fan_hub_diameter_mm")
    assert paths["orin_intake"].need_mm2 == pytest.approx(ratio * math.pi / 4 * (d * d - hub * hub))
    assert all(p.windows for p in paths.values())
    assert all(w.axis == 2 for w in paths["orin_intake"].windows)
    assert {w.axis for w in paths["blower_left_exhaust"].windows} == {0, 1}


def test_the_card_stands_the_rule_s_height_over_the_devkit(lay, rig):
    gap = lay.compute.card_box.lo[2] - lay.compute.orin_box.hi[2]
    assert gap == pytest.approx(rig.desc.enclosure.vents.inlet_gap_ratio * rig.dim("jetson_agx_orin", "fan_diameter_mm"))
    assert gap >= 60 / 4 - 1e-9


def test_vents_miss_the_pads_lugs_and_controls_and_print_along_their_bridges(lay):
    from cad.layout.case import lug_bounds
    case = lay.case
    blockers = list(lay.handles.pads) + [lug_bounds(case, lay.c, lay.fits, x, s) for x, s in case.lugs]
    for name, (part, pose) in lay.controls.items():   # each control's own body and bezel, a wall round it
        blockers.append(placed_bounds(part.bounds(), pose).grown(lay.fits.min_wall))
    v_rig = lay.rig.desc.enclosure.vents
    for v in case.vents:
        plane = sorted(v.size[k] for k in range(3) if k != _wall_axis(v, case.outer))
        assert plane[0] <= v_rig.slot_width_mm + 1e-9 and plane[1] <= v_rig.slot_length_mm + 1e-9, v
        for b in blockers:
            assert not v.overlaps(b), (v, b)
        axis = _wall_axis(v, case.outer)
        if v.hi[2] > case.split_z + 1e-6 and axis in (1, 2):   # in the lid: long along x, its print direction
            assert v.size[0] > v.size[2 if axis == 1 else 1], v
        elif axis == 1:                                          # in the tray: vertical
            assert v.size[2] > v.size[0], v


@pytest.mark.slow
def test_the_default_rig_passes_and_both_measurements_agree(results, asm):
    r = results["airflow"]
    assert r.ok, r.details
    for name in PATHS:
        d = r.data[name]
        assert d["brep_mm2"] >= d["need_mm2"] and d["stl_mm2"] >= d["need_mm2"], (name, d)
        assert abs(d["brep_mm2"] - d["stl_mm2"]) <= AGREE_REL * d["brep_mm2"] + AGREE_ABS_MM2 * d["slots"]
    g = r.data["orin_inlet_gap"]
    assert g["nearest"] == "zed_link_quad"
    assert g["brep_mm"] == pytest.approx(15.0, abs=1e-3) and g["stl_mm"] == pytest.approx(15.0, abs=0.01)


def _with_case_boxes(asm, drop):
    from cad.assembly import Assembly
    nodes = []
    for n in asm.nodes:
        if n.name in ("case_lower", "case_lid"):
            spec = dataclasses.replace(n.spec.spec, boxes=tuple(b for b in n.spec.spec.boxes if b not in drop))
            n = dataclasses.replace(n, spec=dataclasses.replace(n.spec, spec=spec), _shape=None)
        nodes.append(n)
    return Assembly(asm.rig, asm.layout, nodes, asm.cache)


@pytest.mark.slow
def test_a_roof_without_its_slots_fails_naming_the_devkit_intake(asm):
    from cad import checks
    roof = {v for v in asm.layout.case.vents if _wall_axis(v, asm.layout.case.outer) == 2}
    r = checks.check_airflow(_with_case_boxes(asm, roof))
    assert not r.ok
    assert r.data["orin_intake"]["brep_mm2"] == pytest.approx(0.0, abs=1.0)
    assert r.data["orin_intake"]["stl_mm2"] == pytest.approx(0.0, abs=1.0)
    bad = [d for d in r.details if "free through" in d and "under" in d]
    assert [d.split(":")[0] for d in bad] == ["orin_intake"]
    assert r.data["orin_exhaust"]["brep_mm2"] >= r.data["orin_exhaust"]["need_mm2"]   # the other paths untouched


@pytest.mark.slow
def test_one_front_slot_filled_fails_that_blower_only(asm):
    from cad import checks
    front = {v for v in asm.layout.case.vents if _wall_axis(v, asm.layout.case.outer) == 0 and v.centre[1] > 0}
    r = checks.check_airflow(_with_case_boxes(asm, front))
    assert not r.ok
    problems = [d for d in r.details if "under" in d and "free through" in d]
    assert [d.split(":")[0] for d in problems] == ["blower_left_exhaust"]
    # what is left is the two side slots beside the fin bank, 3 x 23.5 mm each (a wall under the front lug)
    assert r.data["blower_left_exhaust"]["brep_mm2"] == pytest.approx(2 * 3.0 * 23.5, abs=0.5)
    assert r.data["blower_left_exhaust"]["stl_mm2"] == pytest.approx(2 * 3.0 * 23.5, abs=0.5)


@pytest.mark.slow
def test_the_card_lowered_back_to_1_mm_fails_naming_the_intake_and_the_card(asm):
    from cad import checks
    from cad.assembly import Assembly
    from platform_tools.rig.frames import Pose
    orin_top = asm.layout.compute.orin_box.hi[2]
    nodes = [dataclasses.replace(n, pose=Pose(n.pose.R, (n.pose.t[0], n.pose.t[1], orin_top + 1.0)), _shape=None)
             if n.name == "zed_link_quad" else n for n in asm.nodes]
    r = checks.check_airflow(Assembly(asm.rig, asm.layout, nodes, asm.cache))
    assert not r.ok
    line = next(d for d in r.details if "over the devkit's fan inlet" in d)
    assert line.startswith("orin_intake: zed_link_quad is 1.0 mm over")
    assert r.data["orin_inlet_gap"]["brep_mm"] == pytest.approx(1.0, abs=1e-3)
    assert r.data["orin_inlet_gap"]["stl_mm"] == pytest.approx(1.0, abs=0.01)


def _trimesh_free_mm2(mesh, boxes, axis: int, pitch: float) -> float:
    """The area through ``boxes`` ((lo, hi) arrays (3,), each spanning the wall along ``axis``) that no triangle
    of ``mesh`` stops: trimesh's ray caster along +``axis`` on a grid of ``pitch`` cells from the boxes' corner
    (not aligned with the slots), each ray from 1 mm before the wall to 1 mm past it."""
    from tests.cad.trimesh_rays import ray_hits
    lo, hi = np.min([b[0] for b in boxes], axis=0), np.max([b[1] for b in boxes], axis=0)
    # only the triangles near these slots reach the ray caster (a broad phase; trimesh does the rest)
    near = np.all(mesh.triangles.max(axis=1) >= lo - 1.0, axis=1) & np.all(mesh.triangles.min(axis=1) <= hi + 1.0, axis=1)
    tri, normals = np.asarray(mesh.triangles)[near], np.asarray(mesh.face_normals)[near]
    u, w = (k for k in range(3) if k != axis)
    uu, ww = np.meshgrid(np.arange(lo[u] + pitch / 2, hi[u], pitch), np.arange(lo[w] + pitch / 2, hi[w], pitch),
                         indexing="ij")
    inside = np.zeros(uu.shape, bool)
    for blo, bhi in boxes:
        inside |= (uu >= blo[u]) & (uu < bhi[u]) & (ww >= blo[w]) & (ww < bhi[w])
    origins = np.zeros((int(inside.sum()), 3))
    origins[:, u], origins[:, w], origins[:, axis] = uu[inside], ww[inside], lo[axis] - 1.0
    dirs = np.zeros_like(origins)
    dirs[:, axis] = 1.0
    _, ray, loc = ray_hits(tri, normals, origins, dirs)
    stopped = np.zeros(len(origins), bool)
    stopped[ray[loc[:, axis] <= hi[axis] + 1.0]] = True
    return float((~stopped).sum()) * pitch * pitch


@pytest.mark.slow
def test_trimesh_reading_the_exported_lid_finds_the_b_rep_s_roof_area(asm, tmp_path):
    """The lid exported to STL, read by trimesh, cast through by trimesh's ray caster on a grid of its
    own (0.2 mm, not aligned with the slots), over the roof's two inner rows of slots on the left: their
    free area equals the B-rep's within the grid's edge error (half a cell along every slot edge)."""
    import cadquery as cq
    from cad.airflow import brep_free_area_mm2
    path = tmp_path / "case_lid.stl"
    lid = asm.node("case_lid").shape(asm.cache)
    cq.exporters.export(lid, str(path), "STL", tolerance=0.1, angularTolerance=0.2)
    mesh = trimesh.load(str(path), process=False)
    intake = next(p for p in air_paths(asm.layout) if p.name == "orin_intake")
    rows = sorted({round(w.box.centre[1], 3) for w in intake.windows if w.box.centre[1] > 0})[:2]
    windows = tuple(w for w in intake.windows if round(w.box.centre[1], 3) in rows)
    assert len(windows) == 8
    pitch = 0.2
    free = _trimesh_free_mm2(mesh, [(np.array(w.box.lo), np.array(w.box.hi)) for w in windows], 2, pitch)
    brep = brep_free_area_mm2([lid], windows)
    edge = sum(2 * (w.box.size[0] + w.box.size[1]) for w in windows) * pitch / 2
    # the built lid has exactly the slots the windows were grown from (one cell each side), 3 mm wide
    slots = sum((w.box.size[0] - 2 * w.step[0]) * (w.box.size[1] - 2 * w.step[1]) for w in windows)
    assert all(w.box.size[1] - 2 * w.step[1] == pytest.approx(3.0) for w in windows)
    assert brep == pytest.approx(slots, rel=1e-3)
    assert abs(free - brep) <= edge, (free, brep, edge)


def test_a_hub_as_wide_as_the_fan_is_one_line_naming_the_key():
    # a fan with no free ring would need nothing: the design is impossible, one line naming the key, before any
    # geometry (cad/layout/constraints.py: exit 2 from export, check and params like every impossible override)
    from cad.layout import design_problems
    from platform_tools.rig import load_rig
    ps = design_problems(load_rig(overrides=["parts.jetson_agx_orin.dims.fan_hub_diameter_mm.value=70"]))
    assert [str(p) for p in ps] == ["parts.jetson_agx_orin.dims.fan_hub_diameter_mm: 70 mm, expected 0 to under "
                                    "fan_diameter_mm (60 mm): the fan would have no free ring"]
    assert not design_problems(load_rig(overrides=["parts.jetson_agx_orin.dims.fan_hub_diameter_mm.value=59.9"]))

# ----------------------------------------------------------------------------- what stands in the gap round the fan
def _gap(radius=30.0, height=15.0):
    from cad.inlet_gap import Gap
    return Gap((0.0, 0.0), radius, 0.0, height, Bounds((-80.0, -80.0, 0.0), (80.0, 80.0, height)))


def _trimesh_post(x, y, radius, height, sections):
    return trimesh.creation.cylinder(radius=radius, height=height, sections=sections,
                                     transform=trimesh.transformations.translation_matrix((x, y, height / 2)))


def test_a_round_post_hides_its_arc_on_both_readings():
    """A 6 mm post 40 mm from the fan's axis hides 2 asin(3/40) of the turn over its 15 mm: on the
    cylinder of R = 30 mm, 15 x 30 x 2 asin(3 / 40) = 67.5 mm^2 (the B-rep from OpenCascade's solid, the
    rays from a mesh trimesh makes)."""
    from cad.solids import cylinder
    from cad.inlet_gap import brep_blocked_mm2, gap_reading, mesh_blocked_mm2
    gap = _gap()
    expect = 15.0 * 30.0 * 2 * math.asin(3.0 / 40.0)
    brep, by = brep_blocked_mm2(gap, {"post": cylinder(6.0, 15.0, (40.0, 0.0, 0.0))})
    assert by == ("post",) and brep == pytest.approx(expect, rel=5e-3)
    rays = mesh_blocked_mm2(gap, _trimesh_post(40.0, 0.0, 3.0, 15.0, 128).triangles)
    assert rays == pytest.approx(expect, abs=4.0)                 # one 0.5 deg cell at each edge of the arc
    # a post beyond the card's footprint, or above the gap, hides nothing
    far = gap_reading(gap, 100.0, {"far": cylinder(6.0, 15.0, (90.0, 0.0, 0.0)),
                                   "above": cylinder(6.0, 5.0, (40.0, 0.0, 15.5))},
                      np.concatenate([_trimesh_post(90.0, 0.0, 3.0, 15.0, 32).triangles]))
    assert far.blocked_brep_mm2 == 0.0 and far.blocked_stl_mm2 == 0.0 and far.ok


@pytest.mark.slow
def test_posts_ringed_close_round_the_fan_fail_naming_them():
    """Twelve 5.8 mm posts 34 mm out hide over half the side: the rule fails, naming them, on both readings."""
    from cad.solids import cylinder
    from cad.inlet_gap import gap_problems, gap_reading
    gap = _gap()
    pts = [(34 * math.cos(a), 34 * math.sin(a)) for a in np.arange(12) * math.pi / 6]
    shapes = {f"post_{k}": cylinder(5.8, 15.0, (x, y, 0.0)) for k, (x, y) in enumerate(pts)}
    tri = np.concatenate([_trimesh_post(x, y, 2.9, 15.0, 64).triangles for x, y in pts])
    g = gap_reading(gap, math.pi / 4 * (60 ** 2 - 24 ** 2), shapes, tri)
    expect = 12 * 15.0 * 30.0 * 2 * math.asin(2.9 / 34.0)
    assert g.blocked_brep_mm2 == pytest.approx(expect, rel=5e-3) and g.blocked_stl_mm2 == pytest.approx(expect, rel=0.03)
    assert not g.ok and g.agree
    (line,) = gap_problems(g)
    assert line.startswith("orin_intake: post_0, post_1") and "under its free ring 2375 mm^2" in line


@pytest.mark.slow
def test_the_card_s_standoffs_are_measured_in_the_gap_and_pass(results, asm):
    """The real layout: the four standoffs stand in the gap (the clear height over the fan is still the
    card's 15 mm), each hides between the arcs of its inscribed and circumscribed circles (across flats
    and across corners, an independent bound from the rig's sizes), and the side left open passes."""
    r = results["airflow"]
    s = r.data["orin_inlet_side"]
    names = {n.name for n in asm.nodes if n.props.get("kind") == "standoff"}
    assert len(names) == 4 and names <= set(s["in_gap"])
    assert r.data["orin_inlet_gap"]["nearest"] == "zed_link_quad"
    so, cp = asm.layout.compute.card_standoff, asm.layout.compute
    ob = cp.orin_box
    R, h = cp.fan_diameter / 2, cp.card_box.lo[2] - ob.hi[2]
    lo = hi = 0.0
    for p in cp.card_standoff_poses:
        d = math.hypot(p.t[0] - ob.centre[0], p.t[1] - ob.centre[1])
        lo += h * R * 2 * math.asin(so.across_flats_mm / 2 / d)
        hi += h * R * 2 * math.asin(so.across_corners_mm / 2 / d)
    for key in ("open_brep_mm2", "open_stl_mm2"):
        blocked = s["side_mm2"] - s[key]
        assert lo - 4 * 2.0 <= blocked <= hi + 4 * 2.0, (key, blocked, lo, hi)
        assert s[key] >= s["need_mm2"], (key, s)
    assert s["side_mm2"] == pytest.approx(2 * math.pi * R * h, abs=0.05)      # the data rounds to 0.1 mm^2


@pytest.mark.slow
def test_the_standoffs_moved_round_the_fan_s_axis_fail_the_intake_not_its_clear_height(asm):
    """The card's four standoffs moved 8 mm round the fan's axis (on its disc, under the card): the clear
    height over the fan ignores them (still the card's 15 mm), the gap's side rule fails naming them."""
    from cad import checks
    from cad.assembly import Assembly
    from platform_tools.rig.frames import Pose
    c = asm.layout.compute.orin_box.centre
    ring = iter([(8, 0), (0, 8), (-8, 0), (0, -8)])
    moved_ = {}
    nodes = []
    for n in asm.nodes:
        if n.props.get("kind") == "standoff":
            dx, dy = next(ring)
            moved_[n.name] = (c[0] + dx, c[1] + dy)
            n = dataclasses.replace(n, pose=Pose(n.pose.R, (c[0] + dx, c[1] + dy, n.pose.t[2])), _shape=None)
        elif n.props.get("host", "").startswith("card_standoff_") and n.category == "fastener":
            continue                                              # their screws stay in the card's holes: leave them out
        nodes.append(n)
    r = checks.check_airflow(Assembly(asm.rig, asm.layout, nodes, asm.cache))
    assert not r.ok
    bad = [d for d in r.details if "under the card hide" in d]
    assert len(bad) == 1 and all(name in bad[0] for name in moved_), r.details
    assert r.data["orin_inlet_gap"]["brep_mm"] == pytest.approx(15.0, abs=1e-3)
    assert r.data["orin_inlet_gap"]["nearest"] == "zed_link_quad"
    s = r.data["orin_inlet_side"]
    assert s["open_brep_mm2"] < s["need_mm2"] and s["open_stl_mm2"] < s["need_mm2"]


# ----------------------------------------------------------------------------- each blower's intake on its own
def test_an_opening_feeds_an_inlet_only_in_the_wall_it_faces_and_within_reach():
    from cad.airflow import feeds_inlet
    outer = Bounds((-100, -50, -40), (10, 50, 30))
    centre, facing = np.array([-40.0, 45.0, -10.0]), np.array([0.0, 1.0, 0.0])      # an inlet facing +y
    slot = lambda x, y, z: Bounds((x - 1.5, y - 1.0, z - 10.0), (x + 1.5, y + 1.0, z + 10.0))   # noqa: E731
    assert feeds_inlet(slot(-40 + 15, 50, -10 + 20), 1, outer, centre, facing, 26.0)        # 25 mm out: in
    assert not feeds_inlet(slot(-40 + 18, 50, -10 + 20), 1, outer, centre, facing, 26.0)    # 26.9 mm out: beyond
    assert not feeds_inlet(slot(-40, -50, -10), 1, outer, centre, facing, 26.0)             # the other side wall
    assert not feeds_inlet(Bounds((-41, 20, 29), (-39, 23, 31)), 2, outer, centre, facing, 26.0)   # the roof


def test_a_slot_two_paths_count_is_one_problem():
    from cad.airflow import AirPath, _shared_slots
    w = Window(Bounds((0, 0, 0), (3, 2.4, 20)), 1, (0.25, 0.25))
    other = Window(Bounds((6, 0, 0), (9, 2.4, 20)), 1, (0.25, 0.25))
    a, b = AirPath("a", "fan a", 1.0, 1.5, (w, other), "x"), AirPath("b", "fan b", 1.0, 1.5, (w,), "x")
    (line,) = _shared_slots([a, b])
    assert "counted by a and b" in line and "(1.5, 1.2, 10.0)" in line
    assert _shared_slots([a]) == []


def test_each_blower_intake_is_the_slots_round_its_own_inlet_and_no_other_path_s(lay, rig):
    """Every intake slot is in the side wall the fan's inlet faces (the built fan's +z face, on the fan's side),
    within one inlet diameter of the inlet's centre (taken here from the fan's box, not the check's pose
    arithmetic); no slot is counted by two paths."""
    paths = {p.name: p for p in air_paths(lay)}
    d = rig.dim("fan_3010_5v", "inlet_diameter_mm")
    for side, f in lay.cooling.fans.items():
        ws = paths[f"blower_{side}_intake"].windows
        assert len(ws) >= 6
        for w in ws:
            c = np.asarray(w.box.centre)
            assert w.axis == 1 and np.sign(c[1]) == f.sign
            assert math.hypot(c[0] - f.box.centre[0], c[2] - f.box.centre[2]) <= d + 1e-9
            assert c[2] < lay.case.split_z and w.box.hi[0] <= f.box.hi[0] + w.step[0] + 1e-9   # the tray, behind the outlet
    boxes = [w.box for p in paths.values() for w in p.windows]
    assert len(boxes) == len(set(boxes))


def _intake_vents(asm, sign):
    """The tray's side-wall slots on one side from one inlet diameter behind the fan's centre to its outlet
    face: found here from the vents' boxes, not by the check's rule."""
    lay = asm.layout
    f = next(f for f in lay.cooling.fans.values() if f.sign == sign)
    d = asm.rig.dim("fan_3010_5v", "inlet_diameter_mm")
    return {v for v in lay.case.vents if _wall_axis(v, lay.case.outer) == 1 and np.sign(v.centre[1]) == sign
            and f.box.centre[0] - d <= v.centre[0] <= f.box.hi[0] and v.hi[2] <= lay.case.split_z}


@pytest.mark.slow
def test_the_left_blower_s_slots_closed_fail_its_intake_only(asm):
    from cad import checks
    r = checks.check_airflow(_with_case_boxes(asm, _intake_vents(asm, 1.0)))
    assert not r.ok
    bad = [d for d in r.details if "free through" in d and "under" in d]
    assert [d.split(":")[0] for d in bad] == ["blower_left_intake"]
    assert r.data["blower_left_intake"]["brep_mm2"] == pytest.approx(0.0, abs=1.0)
    assert r.data["blower_left_intake"]["stl_mm2"] == pytest.approx(0.0, abs=1.0)
    right = r.data["blower_right_intake"]
    assert right["brep_mm2"] >= right["need_mm2"] and right["stl_mm2"] >= right["need_mm2"]


@pytest.mark.slow
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_trimesh_reading_the_exported_tray_finds_each_intake_s_area(asm, tmp_path, sign):
    """The tray exported to STL, read by trimesh, cast through along y by trimesh's ray caster on a 0.2 mm
    grid of its own over the slots round one fan's inlet (found from the vents' boxes, not the check's
    windows): their free area is the B-rep's within the grid's edge error, and at least the need."""
    import cadquery as cq
    path = tmp_path / "case_lower.stl"
    tray = asm.node("case_lower").shape(asm.cache)
    cq.exporters.export(tray, str(path), "STL", tolerance=0.1, angularTolerance=0.2)
    mesh = trimesh.load(str(path), process=False)
    vents = sorted(_intake_vents(asm, sign), key=lambda v: (v.lo[0], v.lo[2]))
    assert len(vents) >= 6
    o, i = asm.layout.case.outer, asm.layout.case.interior
    y0, y1 = (i.hi[1], o.hi[1]) if sign > 0 else (o.lo[1], i.lo[1])
    pitch = 0.2
    boxes = [(np.array([v.lo[0] - pitch, y0, v.lo[2] - pitch]), np.array([v.hi[0] + pitch, y1, v.hi[2] + pitch]))
             for v in vents]
    free = _trimesh_free_mm2(mesh, boxes, 1, pitch)
    side = "left" if sign > 0 else "right"
    intake = next(p for p in air_paths(asm.layout) if p.name == f"blower_{side}_intake")
    from cad.airflow import brep_free_area_mm2
    brep = brep_free_area_mm2([tray], intake.windows)
    edge = sum(2 * (v.size[0] + v.size[2]) for v in vents) * pitch / 2
    slots = sum(v.size[0] * v.size[2] for v in vents)
    assert brep == pytest.approx(slots, rel=1e-3)               # every slot the layout placed is cut through the tray
    assert abs(free - brep) <= edge, (free, brep, edge)
    assert min(free, brep) >= intake.need_mm2


def _converter_slots(lay):
    """The right side wall's slots over the converter, found from the vents' boxes (not the check's windows):
    crossing the wall on the converter's side, overlapping its length, wholly above its top."""
    cb, o = lay.power.converter_box, lay.case.outer
    s = np.sign(cb.centre[1])
    return [v for v in lay.case.vents if _wall_axis(v, o) == 1 and np.sign(v.centre[1]) == s
            and v.lo[0] < cb.hi[0] and cb.lo[0] < v.hi[0] and v.lo[2] >= cb.hi[2]]


@pytest.mark.slow
def test_the_converter_stands_in_the_devkit_s_exhaust_stream(results, asm, rig):
    """The converter (TEP 150-2412WI) loses load x (1/eff - 1) as heat, the load summed here from the rig's parts'
    power; it stands between the devkit's right face and the wall, and the lid's side slots over it (found from
    the vents' boxes) are what both readings measure: each slot's 3 mm x its length, within a ray cell's edge."""
    lay = asm.layout
    d = results["airflow"].data["converter_stream"]
    eff = rig.part("dc_converter").efficiency.value
    load = sum(n * rig.part(p).power_w.value for p, n in (("zed_x", 1), ("boson_640", 2), ("fan_3010_5v", 2),
                                                          ("jetson_agx_orin", 1), ("zed_link_quad", 1)))
    assert d["loss_w"] == pytest.approx(load * (1 / eff - 1), abs=0.01)
    assert d["beside"] == "-y"
    slots = _converter_slots(lay)
    assert d["slots"] == len(slots) > 0
    w = rig.desc.enclosure.vents.slot_width_mm
    area = sum(w * (v.hi[0] - v.lo[0]) if v.size[0] > v.size[2] else w * v.size[2] for v in slots)
    assert d["brep_mm2"] == pytest.approx(area, rel=0.01) and d["stl_mm2"] == pytest.approx(area, rel=0.01)


@pytest.mark.slow
def test_the_slots_over_the_converter_filled_fail_naming_it(asm):
    from cad import checks
    r = checks.check_airflow(_with_case_boxes(asm, set(_converter_slots(asm.layout))))
    assert not r.ok
    assert r.data["converter_stream"]["brep_mm2"] == pytest.approx(0.0, abs=1.0)
    assert any(p.startswith("dc_converter: loses") and "stands in no air path: no orin_exhaust slot lies over it" in p
               for p in r.details), r.details


def test_a_converter_away_from_the_devkit_s_side_stands_in_no_stream(lay):
    """Moved ahead of the devkit (its front end 10 mm past the devkit's front face), the converter faces no
    exhaust face: no stream, no slots. Where it stands, the stream is the right face's."""
    from cad.airflow import converter_stream
    paths = air_paths(lay)
    assert converter_stream(lay, paths)[0] == "-y" and converter_stream(lay, paths)[1]
    p = lay.power
    ahead = p.converter_pose.t[0] + (lay.compute.orin_box.hi[0] - p.converter_box.lo[0]) + 10.0
    from platform_tools.rig.frames import Pose
    moved = Pose(p.converter_pose.R, np.array([ahead, *p.converter_pose.t[1:]]))
    lay2 = dataclasses.replace(lay, power=dataclasses.replace(p, converter_pose=moved))
    assert lay2.power.converter_box.lo[0] == pytest.approx(lay.compute.orin_box.hi[0] + 10.0)
    assert converter_stream(lay2, paths) == ("", ())
