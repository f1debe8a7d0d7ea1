"""The power and sync parts as placed parts (issue 16, items 1 and 2): the cable gland in its hole in the
floor, the under-voltage cut-off on its bosses, a sync breakout on each Boson, each in the assembly,
the BOM's count and the guide's steps; the check that fails a blocked locknut or plug."""
from __future__ import annotations

import numpy as np
import pytest

from cad import checks
from cad.assembly_order import load_steps
from cad.electrical import electrical_checks, gland_check
from cad.geom import Bounds, box, moved
from platform_tools.rig.loader import load_rig

pytestmark = pytest.mark.slow


def test_parts_are_placed_counted_and_in_the_guide(asm, rig):
    from cad.assembly import assembly_tree
    counts = assembly_tree(asm, volumes=False)["counts"]
    assert counts["cable_gland"] == 1 and counts["undervoltage_cutoff"] == 1
    assert counts["boson_sync_breakout"] == counts["boson_640"] == 2
    steps = {n: s.id for s in load_steps([n.name for n in asm.nodes]) for n in s.nodes}
    # the gland goes into the empty tray (its locknut's socket needs the room); the cut-off in the power step
    assert steps["cable_gland"] == "tray"
    assert steps["undervoltage_cutoff"] == steps["screw_cutoff_0"] == steps["insert_cutoff_1"] == "power"
    assert steps["sync_breakout_left"] == steps["boson_left"]


def test_check_passes_and_measures_the_table_hole(results, rig):
    r = results["power and sync parts"]
    assert r.ok, r.details
    assert r.data["gland_hole_mm"] == pytest.approx(rig.dim("cable_gland", "hole_diameter_mm"), abs=0.01)


def test_gland_hole_read_back_from_the_exported_stl(asm, rig, tmp_path):
    """Independent of the check's B-rep distance: trimesh sections the tray's STL mid-floor and the loop
    around the gland's axis is the table's hole."""
    import cadquery as cq
    import trimesh
    path = tmp_path / "case_lower.stl"
    cq.exporters.export(asm.node("case_lower").shape(asm.cache), str(path), "STL", tolerance=0.01, angularTolerance=0.05)
    mesh = trimesh.load(str(path))
    x, y, z = asm.layout.power.gland_pose.t
    sec = mesh.section(plane_origin=(0, 0, z + asm.layout.fits.wall / 2), plane_normal=(0, 0, 1))
    pts = np.asarray(sec.vertices)[:, :2]
    r = np.hypot(pts[:, 0] - x, pts[:, 1] - y)
    loop = r[r < 10.0]
    assert len(loop) > 20
    d = rig.dim("cable_gland", "hole_diameter_mm")
    assert loop.max() == pytest.approx(d / 2, abs=0.02) and loop.min() == pytest.approx(d / 2, abs=0.02)
    # nothing else of the tray cuts the floor near it: the next material edge is beyond the locknut's circle
    nut = rig.dim("cable_gland", "locknut_across_corners_mm")
    assert not np.any((r > d / 2 + 0.05) & (r < nut / 2))


def test_cutoff_stands_on_its_bosses(asm):
    """The tray has solid bosses under the cut-off's two holes, with an insert hole in each."""
    p, floor = asm.layout.power, asm.layout.case.interior.lo[2]
    tray = asm.node("case_lower").shape(asm.cache)
    ins = asm.layout.fits.insert
    for x, y, d, h in p.cutoff_bosses:
        ring = (x + (ins.hole_diameter_mm + d) / 4, y, floor + h / 2)     # between the insert hole and the boss's edge
        assert tray.isInside(cq_vec(ring))
        assert not tray.isInside(cq_vec((x, y, floor + h - 1.0)))          # the insert's hole
    assert p.cutoff_pose.t[2] == pytest.approx(floor + max(b[3] for b in p.cutoff_bosses))


def cq_vec(p):
    import cadquery as cq
    return cq.Vector(*p)


def test_a_part_over_the_locknut_fails(asm):
    x, y, _ = asm.layout.power.gland_pose.t
    floor = asm.layout.case.interior.lo[2]
    block = box(Bounds((x - 3, y - 3, floor + 20), (x + 3, y + 3, floor + 25)))
    r = checks.check_power_parts(asm, extra=[("test_block", block)])
    assert not r.ok
    assert any("locknut cannot be tightened" in p and "test_block" in p for p in r.details), r.details


def test_a_part_behind_a_breakout_fails(asm):
    pose = asm.layout.power.breakout_poses["left"]
    behind = moved(box(Bounds((-12, -2, -2), (-8, 2, 2))), pose)   # 3-7 mm behind the board's rear face
    r = checks.check_power_parts(asm, extra=[("test_block", behind)])
    assert not r.ok
    assert any(p.startswith("sync_breakout_left: no room to plug") and "test_block" in p for p in r.details), r.details
    assert not any(p.startswith("sync_breakout_right: no room") for p in r.details)


COUNTS = {"jetson_agx_orin": 1, "zed_x": 1, "boson_640": 2, "zed_link_quad": 1, "fan_3010_5v": 2}


@pytest.mark.parametrize("override, name", [
    ("parts.cable_gland.dims.cable_diameter_mm.value=8", "cable gland"),       # the seal cannot grip it
    ("parts.cable_gland.dims.hole_diameter_mm.value=12", "cable gland"),       # under the 12.5 mm thread
    ("parts.undervoltage_cutoff.rating_a.value=5", "cut-off rating"),          # under the 7.5 A fuse
    ("parts.undervoltage_cutoff.supply_v.min=16", "cut-off rating"),           # dead above the 15 V it must act at
])
def test_electrical_fails_a_bad_gland_or_cutoff(override, name):
    res = {r.name: r for r in electrical_checks(load_rig(overrides=[override]), COUNTS)}
    assert not res[name].ok, res[name].text
    assert all(r.ok for n, r in res.items() if n != name), [r.text for r in res.values() if not r.ok]


def test_default_gland_grips_the_lead():
    assert gland_check(load_rig()).ok
