"""The checks pass on the design and catch what they are meant to catch."""
import dataclasses

import cadquery as cq
import pytest

from cad import checks
from cad.assembly import Assembly
from cad.geom import Bounds
from cad.solids import box

#: every test needs the built CAD assembly: the quick loop (make test-fast) leaves them to make test
pytestmark = pytest.mark.slow


@pytest.mark.slow
def test_every_check_passes_on_the_default_design(results):
    failed = {n: r.details[:5] for n, r in results.items() if not r.ok}
    assert not failed


def test_intended_overlaps_are_measured_not_assumed(asm, results):
    intended = checks.intended_overlaps(asm)
    inserts = [j for j in asm.layout.joints if j.kind == "insert"]
    assert len([k for k, (v, _) in intended.items() if v > 0]) >= len(inserts)
    allowed = [d for d in results["interference"].details if "intended" in d and "mm^3 (" in d]
    assert len(allowed) >= len(inserts)
    assert not any("MISMATCH" in d for d in allowed)


def _with_node_moved(asm, name, dx=0.0, dy=0.0, dz=0.0):
    import numpy as np
    from platform_tools.rig.frames import Pose
    nodes = []
    for n in asm.nodes:
        if n.name == name:
            n = dataclasses.replace(n, pose=Pose(np.eye(3), (dx, dy, dz)) @ n.pose, _shape=None)
        nodes.append(n)
    return Assembly(asm.rig, asm.layout, nodes, asm.cache)


@pytest.fixture(scope="module")
def two_defects(asm):
    """One modified build for the two interference tests (the check over the whole assembly is the slow part):
    the fuse lifted into the computer, and a thermal-bar insert pushed 1.5 mm deeper than its hole. The two
    defects are far apart, so each test reads its own one."""
    moved = _with_node_moved(asm, "blade_fuse", dy=-15.0, dz=5.0)
    moved = _with_node_moved(moved, "insert_thermal_mount_0", dz=1.5)
    return checks.check_interference(moved)


@pytest.mark.slow
def test_a_real_clash_is_found(two_defects):
    r = two_defects
    assert not r.ok
    problems = r.details[:r.details.index("intended:")]
    assert any("blade_fuse" in d and "jetson_agx_orin" in d for d in problems), problems


@pytest.mark.slow
def test_an_insert_in_the_wrong_place_fails_its_allowance(two_defects):
    r = two_defects
    assert not r.ok
    # its own problem line (before the "intended:" list, which names every insert, passing or not)
    problems = r.details[:r.details.index("intended:")]
    assert any("insert_thermal_mount_0" in d and "intended overlap measures" in d for d in problems), problems


def test_fov_obstruction_is_named(asm):
    lay = asm.layout
    obstacle = box(Bounds((lay.case.outer.hi[0] + 40, -20, -10), (lay.case.outer.hi[0] + 45, 20, 10)))
    r = checks.check_fov(asm, extra=[("obstacle", obstacle)])
    assert not r.ok
    assert any("zed_x_left_optical" in d and "obstacle" in d for d in r.details)


def test_battery_path_blocked_is_named(asm):
    b = checks._bounds(asm, asm.node("makita_battery"))
    wall = box(Bounds((b.lo[0] - 30, b.lo[1], b.lo[2]), (b.lo[0] - 20, b.hi[1], b.hi[2])))
    r = checks.check_battery(asm, extra=[("bracket", wall)])
    assert not r.ok and "bracket" in r.summary


def test_min_wall_measures_a_known_plate_and_rib():
    plate = cq.Workplane().box(20, 20, 1.5).val()
    assert checks.min_wall_of(plate) == pytest.approx(1.5, abs=1e-3)
    # two through slots leave a 0.9 mm rib between them
    ribbed = (cq.Workplane().box(20, 20, 5)
              .cut(cq.Workplane().box(20, 1.55, 5).translate((0, -1.225, 0)))
              .cut(cq.Workplane().box(20, 1.55, 5).translate((0, 1.225, 0))).val())
    assert checks.min_wall_of(ribbed) == pytest.approx(0.9, abs=1e-3)


def test_vent_area_is_measured_on_the_walls(asm, results):
    r = results["vent area"]
    lay = asm.layout
    v = lay.rig.desc.enclosure.vents
    assert r.data["area_mm2"] >= r.data["needed_mm2"]
    # each slot is slot_width x length through the wall, no more
    assert r.data["area_mm2"] <= len(lay.case.vents) * v.slot_width_mm * v.slot_length_mm + 1e-6


def test_mass_counts_every_part(asm, rig):
    mp = checks.mass_properties(asm)
    bought = sum(rig.part(n.part_id).mass_g.value for n in asm.nodes if n.category in ("bought", "fastener"))
    assert mp["mass_g"] > bought
    assert mp["mass_g"] < bought + 2000
