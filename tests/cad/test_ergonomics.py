"""Ergonomics (cad/ergonomics.py, the grip span, stands-on-a-table and record button checks): the design
passes, and a too-narrow grip, a tipping rig, a rig resting on a camera and a button out of reach fail."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from cad import checks
from cad.assembly import Assembly
from cad.ergonomics import Grip, convex_hull, distance_to_grip_mm, stability, tipping_edges
from platform_tools.rig.frames import Pose


def test_a_box_on_a_table_tips_where_the_geometry_says():
    # by hand: a 100 x 60 footprint, centre of mass 50 mm up over its middle: 45 deg over the long
    # sides' edges... over the x edges atan(50/50), over the y edges atan(30/50)
    pts = np.array([[x, y] for x in (-50, 50) for y in (-30, 30)] + [[0, 0], [10, 5]], float)
    hull = convex_hull(pts)
    assert len(hull) == 4
    angles = sorted(round(e.angle_deg, 6) for e in tipping_edges(hull, np.array([0.0, 0, 50]), 0.0))
    assert angles == pytest.approx([math.degrees(math.atan2(30, 50))] * 2 + [45.0] * 2)
    # the centre of mass moved 45 mm forward: 5 mm inside the front edge
    e = max(tipping_edges(hull, np.array([45.0, 0, 50]), 0.0), key=lambda e: e.towards[0])
    assert e.distance_mm == pytest.approx(5.0) and e.angle_deg == pytest.approx(math.degrees(math.atan2(5, 50)))
    bottom = {"box": np.column_stack([pts, np.zeros(len(pts))])}
    assert stability(bottom, np.array([45.0, 0, 50]), 10.0)[0] is False
    assert stability(bottom, np.array([0.0, 0, 50]), 10.0)[0] is True


def test_distance_to_a_grip_by_hand():
    g = Grip("g", (0, 0, 0), (100, 0, 0), 16.0)
    assert distance_to_grip_mm((50, 0, 40), g) == pytest.approx(24.0)
    assert distance_to_grip_mm((130, 0, 40), g) == pytest.approx(50.0 - 16.0)
    assert distance_to_grip_mm((50, 0, 5), g) == 0.0


@pytest.fixture(scope="module")
def plain(rig):
    from cad.assembly import build
    return build(rig)          # placements only; a shape is built when a check asks for it


@pytest.mark.slow
def test_the_grip_span_passes_and_a_narrow_grip_fails(plain):
    from cad.assembly import build
    from platform_tools.rig import load_rig
    r = checks.check_grip_span(plain)
    assert r.ok and r.data["span_mm"] == pytest.approx(plain.rig.desc.enclosure.handles.grip_length_mm - 32.0)
    narrow = checks.check_grip_span(build(load_rig(None, ["enclosure.handles.grip_length_mm=120"])))
    assert not narrow.ok and "88 mm clear" in narrow.details[0] and "enclosure.handles.grip_length_mm" in narrow.details[0]


def _moved(asm, name, offset):
    nodes = [dataclasses.replace(n, pose=Pose(np.eye(3), offset) @ n.pose, _shape=None) if n.name == name else n
             for n in asm.nodes]
    return Assembly(asm.rig, asm.layout, nodes, asm.cache)


@pytest.mark.slow
def test_the_button_is_in_reach_and_out_of_reach_fails(plain):
    r = checks.check_button_reach(plain)
    assert r.ok and min(r.data.values()) <= plain.rig.desc.enclosure.ergonomics.thumb_reach_mm
    far = checks.check_button_reach(_moved(plain, "record_button", (-130.0, 0.0, -40.0)))
    assert not far.ok and "record_button is" in far.details[0]


@pytest.mark.slow
def test_the_old_rear_wall_button_was_out_of_reach(plain):
    # the button where it was (the rear wall, before the check): 60 mm from the nearest grip
    from cad.layout.controls import place_controls
    from cad.layout.case import Shell
    lay = plain.layout
    shell = Shell(lay.case.interior, lay.case.outer, lay.case.split_z)
    _, pose = place_controls(plain.rig, lay.fits, shell, lay.compute)["record_button"]
    nodes = [dataclasses.replace(n, pose=pose, _shape=None) if n.name == "record_button" else n for n in plain.nodes]
    r = checks.check_button_reach(Assembly(plain.rig, lay, nodes, plain.cache))
    assert not r.ok and min(r.data.values()) > 55.0


@pytest.mark.slow
def test_the_rig_stands_and_a_front_heavy_rig_tips(asm):
    r = checks.check_stands(asm)
    assert r.ok, r.details
    assert r.data["min_tilt_deg"] >= asm.rig.desc.enclosure.ergonomics.min_tilt_deg
    assert not any(n.startswith(("zed_x", "boson")) for n in r.data["resting_on"])
    # a 1 kg lens hood on the front of the ZED: the centre of mass goes forward past what it stands on
    front = (asm.layout.case.outer.hi[0], 0.0, 0.0)
    heavy = checks.check_stands(asm, extra_masses=[("weight", 1000.0, front)])
    assert not heavy.ok and "tips over" in heavy.summary
    assert heavy.data["min_tilt_deg"] < r.data["min_tilt_deg"]


@pytest.mark.slow
def test_a_rig_resting_on_a_camera_fails(asm):
    low = _moved(asm, "zed_x", (0.0, 0.0, -160.0))      # a ZED hanging below the battery
    r = checks.check_stands(low)
    assert not r.ok and "zed_x" in r.data["resting_on"]
    assert any(d == "it rests on a camera: zed_x" for d in r.details)


# ----------------------------------------------------------------------------- the same verdict from the STL
# An independent path (tests/cad/mesh_paths.py): every node exported to STL as placed, the table at the lowest
# vertex, the support polygon scipy's convex hull of the vertices near it, the centre of mass the rig's part masses
# (config/rig.yaml mass_g; printed and machined parts their mesh volume times the rig's densities) at their meshes'
# trimesh centroids. The centroid assumes each part's mass spread uniformly through its modelled solid -- the
# check's B-rep centre of mass assumes the same of the same solids, so what differs between the paths is the
# STL's chords (0.1 mm) against the check's own tessellation (0.05 mm) of the parts on the table.

#: the paths' angles within this (deg): the hull's corners move by at most the two tessellations' chords
#: (0.1 + 0.05 mm) in plan, the centre of mass by < 0.01 mm, 137 mm up: atan(0.15 / 137) = 0.06 deg
SAME_BAND_DEG = 0.1
#: the STL's chordal tolerance: a vertex within it of the table may be on the table
STL_CONTACT_MM = 0.1


@pytest.fixture(scope="module")
def on_table(asm):
    from tests.cad.mesh_paths import node_meshes, part_masses_g
    meshes = node_meshes(asm)
    return meshes, part_masses_g(asm, meshes)


@pytest.mark.slow
def test_the_stl_stands_as_the_check_says(asm, on_table):
    from cad.ergonomics import TABLE_CONTACT_MM
    from tests.cad.mesh_paths import standing
    meshes, masses = on_table
    r = checks.check_stands(asm)
    # the same contact band as the check (its documented 0.5 mm, read as data)
    s = standing(meshes, masses, TABLE_CONTACT_MM)
    assert s.resting_on == sorted(r.data["resting_on"]) == ["makita_battery"]
    assert s.table_z == pytest.approx(r.data["table_z_mm"], abs=0.05)
    assert np.allclose(s.com, r.data["com_mm"], atol=0.05)
    assert s.min_tilt_deg == pytest.approx(r.data["min_tilt_deg"], abs=SAME_BAND_DEG)
    # only what is within the STL's chord of the table: the battery's flat bottom, not its rounded edges (the
    # check's 0.5 mm band reaches 1.5 mm up each side's rounding, so its support polygon is 3 mm wider across y):
    # the rig tips sooner sideways by the mesh, still past min_tilt_deg
    strict = standing(meshes, masses, STL_CONTACT_MM)
    assert strict.resting_on == ["makita_battery"]
    assert r.data["min_tilt_deg"] - 1.0 < strict.min_tilt_deg < r.data["min_tilt_deg"]
    assert strict.min_tilt_deg >= asm.rig.desc.enclosure.ergonomics.min_tilt_deg


@pytest.mark.slow
def test_the_stl_of_a_front_heavy_rig_tips_too(asm, on_table):
    from cad.ergonomics import TABLE_CONTACT_MM
    from tests.cad.mesh_paths import standing
    meshes, masses = on_table
    front = (asm.layout.case.outer.hi[0], 0.0, 0.0)
    heavy = checks.check_stands(asm, extra_masses=[("weight", 1000.0, front)])
    least = asm.rig.desc.enclosure.ergonomics.min_tilt_deg
    for band in (TABLE_CONTACT_MM, STL_CONTACT_MM):
        s = standing(meshes, masses, band, extra=[("weight", 1000.0, front)])
        assert not heavy.ok and s.min_tilt_deg < least
        # over the front edge (the battery's flat end face, no rounding there): both bands and the check agree
        assert s.min_tilt_deg == pytest.approx(heavy.data["min_tilt_deg"], abs=SAME_BAND_DEG)
