"""The Boson's retaining plate (cad/layout/boson_clamp.py): it reaches the camera, keeps clear of the copper,
presses the core onto its front stop, its screws are typed, counted and drivable, and it prints.

The geometry is measured on the built solids (OpenCascade intersections and distances, the STL read back),
not on the layout's numbers the plate was made from."""
import copy
import dataclasses
import tempfile
from pathlib import Path

import cadquery as cq
import numpy as np
import pytest
from OCP.BRepExtrema import BRepExtrema_DistShapeShape

from cad import checks
from cad.assembly import assembly_tree
from cad.assembly_order import driver_paths, load_steps
from cad.bought.fasteners import fastener_table
from cad.datums import camera_locations, clamp_problems, removes_claimed
from cad.geom import Bounds
from cad.solids import TOUCH_MM3, bounds_of, moved
from cad.layout import DesignError
from cad.layout.boson_clamp import CLAMP_THREAD, place_boson_clamps
from cad.parts.common import on_bed
from cad.printability import analyse, read_stl
from cad.tolerances import clamp_margins
from platform_tools.rig.frames import Pose

SIDES = ("left", "right")


def _dist(a: cq.Shape, b: cq.Shape) -> float:
    d = BRepExtrema_DistShapeShape(a.wrapped, b.wrapped)
    d.Perform()
    return d.Value()


def _overlap(a: cq.Shape, b: cq.Shape) -> float:
    c = a.intersect(b)
    return c.Volume() if c.Solids() else 0.0


def _shifted_along_axis(asm, node: str, mm: float) -> cq.Shape:
    """``node``'s solid moved ``mm`` along its camera's optical axis (forward)."""
    side = node.rsplit("_", 1)[1]
    fwd = asm.layout.cameras.thermal[side].pose.rotate(np.array([1.0, 0.0, 0.0]))
    return moved(asm.node(node).shape(asm.cache), Pose(np.eye(3), tuple(fwd * mm)))


@pytest.mark.slow
@pytest.mark.parametrize("side", SIDES)
def test_the_plate_bears_on_the_core_and_its_foot_stays_off_the_copper(asm, side):
    plate, core, sink = (asm.node(f"{n}_{side}").shape(asm.cache) for n in ("boson_clamp", "boson", "heat_sink"))
    assert _dist(plate, core) < 1e-6 and _overlap(plate, core) < 0.01      # touching, not inside
    assert _overlap(plate, sink) < 0.01
    # pushed forward along the axis it may travel a little under its gap before it lands on the copper, not more
    gap = place_boson_clamps(asm.layout)[side].gap_mm
    assert _overlap(_shifted_along_axis(asm, f"boson_clamp_{side}", gap - 0.05), sink) < 0.01
    assert _overlap(_shifted_along_axis(asm, f"boson_clamp_{side}", gap + 0.3), sink) > 1.0


@pytest.mark.slow
def test_the_plate_and_its_screws_clash_with_nothing_and_engage_their_threads(asm):
    intended = checks.intended_overlaps(asm)
    names = [n.name for n in asm.nodes if "boson_clamp" in n.name]
    assert len(names) == 2 + 6
    hosts = set()
    for name in names:
        s = asm.node(name).shape(asm.cache)
        for other in asm.nodes:
            if other.name == name or not bounds_of(s).overlaps(bounds_of(other.shape(asm.cache)), 1e-6):
                continue
            v = _overlap(s, other.shape(asm.cache))
            key = frozenset((name, other.name))
            if key in intended:
                hosts.add(other.name)
                assert abs(v - intended[key][0]) <= 0.05 * intended[key][0], (name, other.name, v, intended[key])
            else:
                assert v <= TOUCH_MM3, (name, other.name, v)
    assert hosts == {f"{p}_{s}" for p in ("boson", "heat_sink") for s in SIDES}


def test_the_screws_are_typed_from_the_fastener_table_and_counted(asm, rig):
    size = fastener_table().size(CLAMP_THREAD)
    joints = [j for j in asm.layout.joints if j.name.startswith("boson_clamp_")]
    assert {j.screw_id for j in joints} == {size.screw} and {j.thread for j in joints} == {"M1.6"}
    depth = next(m for m in rig.part("boson_640").mounting if m.face.value == "rear").depth_mm
    for j in joints:
        assert 0 < j.engagement_mm <= (depth if j.host.startswith("boson") else 4.0) + 1e-9, j
        assert j.length_mm in fastener_table().stock_lengths_mm
    # the plate's holes are the printer's M1.6 clearance (ISO 273 medium), the copper's the table's tap drill
    plate_holes = {round(h.diameter, 3) for h in asm.layout.holes_for("boson_clamp_left")}
    assert plate_holes == {rig.desc.printing.holes["M1.6"].normal_mm}
    sink_holes = {round(h.diameter, 3) for j in joints for h in j.holes if h.part.startswith("heat_sink")}
    assert sink_holes == {size.tap_drill_mm}
    counts = assembly_tree(asm, volumes=False)["counts"]
    per_key = {k: v for k, v in counts.items() if k.startswith(size.screw)}
    assert sum(per_key.values()) == 6 == len(joints)
    assert counts["boson_clamp_left"] == counts["boson_clamp_right"] == 1


def _with_plate(asm, side: str, plate_spec):
    """A copy of the assembly whose ``boson_clamp_<side>`` is built from ``plate_spec``."""
    out = copy.copy(asm)
    out.nodes = [dataclasses.replace(n, spec=plate_spec, _shape=None) if n.name == f"boson_clamp_{side}" else n
                 for n in asm.nodes]
    return out


@pytest.mark.slow
def test_a_plate_that_does_not_reach_the_camera_fails_the_datum_check(asm):
    assert checks.check_datums(asm).ok
    spec = asm.node("boson_clamp_left").spec
    pad = spec.blocks[2]
    short = Bounds(pad.lo, (pad.hi[0] - 0.5, pad.hi[1], pad.hi[2]))     # the pad 0.5 mm short of the core
    r = checks.check_datums(_with_plate(asm, "left", dataclasses.replace(spec, blocks=spec.blocks[:2] + (short,))))
    assert not r.ok
    bad = [p for p in r.details if "retaining plate" in p and "off boson_clamp_left" in p]
    assert bad and all("0.50 mm off" in p for p in bad), r.details[:6]
    assert not any("boson_clamp_right" in p and "off" in p for p in r.details[:8])


def test_the_plate_presses_the_core_onto_its_stop_inside_its_seat(rig):
    from cad.layout import layout
    locs = camera_locations(layout(rig))
    loc = locs["thermal_left"][-1]
    (cl,) = loc.clamps
    assert clamp_problems(loc, cl)[0] == []
    # pushing backwards: it pulls the core off its stop
    back = tuple(dataclasses.replace(c, normal=tuple(-v for v in c.normal)) for c in cl.contacts)
    assert any("does not press" in p for p in clamp_problems(loc, dataclasses.replace(cl, contacts=back))[0])
    # bearing beside the core, not on it: it would tip the core over the stop's edge
    T = loc.frame
    off = tuple(dataclasses.replace(c, point=tuple(T.apply(T.inverse().apply(np.array(c.point)) + [0, 0, -12.0])))
                for c in cl.contacts)
    assert any("outside" in p for p in clamp_problems(loc, dataclasses.replace(cl, contacts=off))[0])
    # a gap the tolerances can close: the plate may land on the copper first
    worst = sum(abs(v) for _, v, _ in cl.standoff_terms)
    assert worst == pytest.approx(rig.desc.enclosure.heat_sink.tolerance_mm + rig.desc.printing.printer.tolerance_mm
                                  + rig.desc.printing.printer.layer_mm / 2)
    tight = dataclasses.replace(cl, standoff_mm=worst - 0.05)
    assert any("land on heat_sink_left" in p for p in clamp_problems(loc, tight)[0])
    m = clamp_margins(locs)["thermal_left: retaining plate"]
    assert m["margin_mm"] == pytest.approx(cl.standoff_mm - worst) and m["rss_mm"] < m["worst_mm"]


def test_roll_is_clocked_by_the_bore_floor_and_the_plate_cannot_fight_the_bore(rig):
    from cad.layout import layout
    lay = layout(rig)
    loc = camera_locations(lay)["thermal_left"][-1]
    floor = next(f for f in loc.features if f.name.startswith("bore floor"))
    ok, freed = removes_claimed(loc, floor)
    assert ok and "roll" in freed
    # the clamp is no datum: the bore alone holds all six DOF, and the plate's anchors have more play across
    # the axis than the core has in the bore, so the plate cannot pull the core off its bore faces
    assert np.linalg.matrix_rank(loc.rows()) == 6
    cl = place_boson_clamps(lay)["left"]
    assert cl.anchor_play_mm > rig.desc.enclosure.heat_sink.bore_clearance_mm / 2


@pytest.mark.slow
def test_the_plates_screwed_on_in_the_tray_leave_the_anchors_no_driver_path(asm):
    steps = load_steps([n.name for n in asm.nodes])
    cores = next(s for s in steps if s.id == "thermal_cores")
    assert cores.bench and {"boson_clamp_left", "screw_boson_clamp_left_anchor_0"} <= set(cores.nodes)
    ok = driver_paths(asm, steps)
    assert not [p for p in ok.problems if "boson_clamp" in p]
    # the same step done in the tray (after the tray step) instead of on the bench: the floor is under the
    # driver's handle
    in_tray = [dataclasses.replace(s, bench=False) if s is cores else s for s in steps]
    bad = driver_paths(asm, in_tray)
    blocked = {p.split(" ")[0] for p in bad.problems}
    assert blocked == {f"screw_boson_clamp_{s}_anchor_{k}" for s in SIDES for k in (0, 1)}, bad.problems
    assert any("screw_boson_clamp_left_anchor_0" in p and "case_lower" in p for p in bad.problems)


@pytest.mark.slow
@pytest.mark.parametrize("side", SIDES)
def test_the_plate_prints_without_supports_and_keeps_its_walls(asm, rig, side):
    node = asm.node(f"boson_clamp_{side}")
    p = rig.desc.printing.printer
    shape, _ = on_bed(node.local_shape(asm.cache), checks.PRINT_SETUPS[node.part_id], p.bed_mm)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "plate.stl"
        cq.exporters.export(shape, str(path), "STL", tolerance=0.1, angularTolerance=0.2)
        tri = read_stl(path)
    r = analyse(tri, p.max_overhang_deg, p.max_bridge_mm)
    assert r.ok and r.overhang_mm2 == pytest.approx(0.0, abs=0.5)
    assert r.bed_contact_mm2 > 100            # it lies on its back face, not on an edge
    assert checks.min_wall_of(node.local_shape(asm.cache)) >= p.nozzle_mm * p.min_wall_nozzles - 1e-6


def test_a_breakout_too_wide_for_the_plate_is_bad_input_naming_the_key():
    from cad.assembly import build
    from platform_tools.rig import load_rig
    wide = load_rig(overrides=["parts.boson_sync_breakout.envelope_mm.y.value=13"])
    with pytest.raises(DesignError) as e:
        build(wide)
    assert str(e.value).startswith("parts.boson_sync_breakout.envelope_mm.y: ") and "0.8 mm" in str(e.value)
