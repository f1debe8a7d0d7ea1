"""The cable checks seen from the meshes (issue 16, "Proof: STL analysis in the tests independent of the check's own
code path"): each swept cable and every part near it exported to STL and read by trimesh; lengths, bend radii and
interference measured on the triangles (tests/cad/mesh_cables.py: numpy and trimesh, no call into cad/cables.py's
checking code), against what the B-rep check (``check_cables``) reports, and the same deliberate defects failing
both: a cable through a wall, a twin laid on another, a bend at half its radius."""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import pytest

from cad.bought.cables import cable_table
from cad.cables import Route, routes, sweep

trimesh = pytest.importorskip("trimesh")
from tests.cad import mesh_cables as mc  # noqa: E402  (needs trimesh)

KINDS = cable_table().kinds
#: a bend is read over this share of the cable's minimum radius either side of each point (at least 1 mm)
SPAN_SHARE = 0.1
#: lengths agree within this (mm): the check rounds its lengths to 0.1 mm, the sections are chords
LENGTH_TOL_MM = 0.3
#: radii agree within this share (the STL's 0.01 mm chord error on a 5.65 mm bend is 0.2 %) for a bend fitted
#: over at least LONG_ARC_SHARE x its radius of arc (14 deg); a shorter fit (the 16 deg DC bend leaves 2.5 mm of
#: arc between its spans) is held to the minimum within SHORT_REL only: its radius is ill-conditioned
RADIUS_REL, LONG_ARC_SHARE, SHORT_REL = 0.005, 0.25, 0.03


def _span_mm(kind) -> float:
    return max(1.0, SPAN_SHARE * kind.min_bend_radius_mm)


@dataclass
class Cable:
    route: Route
    mesh: "trimesh.Trimesh"
    points: np.ndarray       # the centre line read off the mesh (M, 3)
    radius_mm: float         # the tube's radius from its caps' area
    bends: list


def _cable(route: Route, tmp) -> Cable:
    kind = KINDS[route.kind]
    mesh = mc.read_stl(sweep(route, kind), tmp / f"cable_{route.name}.stl", mc.CABLE_TOLERANCE_MM, mc.CABLE_ANGULAR_RAD)
    pts, r = mc.centreline(mesh)
    bends = [b for b in mc.bends(pts, 3 * kind.min_bend_radius_mm, _span_mm(kind)) if b.arc_mm >= _span_mm(kind)]
    return Cable(route, mesh, pts, r, bends)


@dataclass
class Scene:
    cables: dict[str, Cable]
    parts: dict[str, "trimesh.Trimesh"]
    trees: dict[str, mc.TriangleBoxes]      # each part's and each cable's broad phase, by name
    brep: object                 # check_cables' result on the same assembly

    def part_hits(self, c: Cable) -> dict[str, int]:
        """How many of the cable's inside points each part's mesh contains (only parts that contain some)."""
        pts = mc.inside_points(c.points, c.radius_mm)
        out = {n: int(mc.contains(m, pts, self.trees[n]).sum()) for n, m in self.parts.items()}
        return {n: k for n, k in out.items() if k}


def _parts_near(asm, meshes, tmp) -> dict[str, "trimesh.Trimesh"]:
    from cad.solids import bounds_of
    out = {}
    for n in asm.nodes:
        s = n.shape(asm.cache)
        b = bounds_of(s)
        if any(np.all(np.array(b.lo) <= m.bounds[1] + 0.5) and np.all(np.array(b.hi) >= m.bounds[0] - 0.5) for m in meshes):
            out[n.name] = mc.read_stl(s, tmp / f"part_{n.name}.stl", mc.PART_TOLERANCE_MM, mc.PART_ANGULAR_RAD)
    return out


@pytest.fixture(scope="module")
def scene(asm, results, tmp_path_factory):
    """The cables' and nearby parts' meshes, beside check_cables' result on the same rig (the suite's shared run of
    every check, tests/cad/conftest.py, rather than a second one of its own)."""
    tmp = tmp_path_factory.mktemp("cables_mesh")
    cables = {r.name: _cable(r, tmp) for r in routes(asm)}
    parts = _parts_near(asm, [c.mesh for c in cables.values()], tmp)
    trees = {n: mc.z_boxes(m) for n, m in parts.items()}
    trees |= {f"cable {n}": mc.z_boxes(c.mesh) for n, c in cables.items()}
    return Scene(cables, parts, trees, results["cables"])


# ----------------------------------------------------------------------------- the mesh tools on trimesh's own shapes
def test_containment_by_ray_parity_on_a_trimesh_box_and_cylinder():
    box = trimesh.creation.box((10.0, 10.0, 10.0))
    pts = np.array([[0, 0, 0], [4.9, 4.9, 4.9], [5.1, 0, 0], [0, 0, -20.0], [0, 0, 5.2]])
    assert mc.contains(box, pts).tolist() == [True, True, False, False, False]
    tube = trimesh.creation.cylinder(radius=2.0, height=30.0, sections=64)
    ring = np.array([[1.9 * math.cos(a), 1.9 * math.sin(a), 3.0] for a in np.linspace(0, 6, 7)])
    assert mc.contains(tube, ring).all() and not mc.contains(tube, ring * [1.1, 1.1, 1.0]).any()


def test_circle_fits_and_the_centre_line_of_a_straight_trimesh_tube():
    a = np.linspace(0.0, 1.2, 40)
    arc = np.column_stack([10 + 7.5 * np.cos(a), -3 + 7.5 * np.sin(a), np.full_like(a, 4.0)])
    r, centre = mc.fit_circle(arc)
    assert r == pytest.approx(7.5, rel=1e-9) and np.allclose(centre, [10, -3, 4])
    rr, cc = mc.circle_through(arc[:-4], arc[2:-2], arc[4:])
    assert np.allclose(rr, 7.5) and np.allclose(cc, [10, -3, 4])
    tube = trimesh.creation.cylinder(radius=1.5, height=40.0, sections=48)
    pts, rad = mc.centreline(tube)
    assert rad == pytest.approx(1.5, rel=0.01)                       # a 48-gon's area, not the circle's
    assert mc.polyline_length_mm(pts) == pytest.approx(40.0, abs=1e-6)
    assert np.allclose(pts[:, :2], 0.0, atol=1e-9) and not mc.bends(pts, 50.0, 1.0)
    assert mc.volume_length_mm(tube) == pytest.approx(40.0, rel=1e-9)


# ----------------------------------------------------------------------------- the default rig, both paths
@pytest.mark.slow
def test_every_cable_s_length_from_its_mesh_is_the_length_the_check_reports(scene):
    """The centre line's chords and the volume over the cap's area, both off the exported STL, against the B-rep
    check's route length (straights + R theta)."""
    reported = scene.brep.data["lengths"]
    assert set(reported) == set(scene.cables)
    for name, c in scene.cables.items():
        assert mc.polyline_length_mm(c.points) == pytest.approx(reported[name], abs=LENGTH_TOL_MM), name
        assert mc.volume_length_mm(c.mesh) == pytest.approx(reported[name], abs=LENGTH_TOL_MM), name
        assert c.radius_mm == pytest.approx(KINDS[c.route.kind].diameter_mm / 2, rel=0.01), name


def _corners(route: Route):
    """Each corner of the route's polyline: (waypoint, turn in rad), from the waypoints alone."""
    p = np.asarray(route.points, dtype=float)
    d = np.diff(p, axis=0)
    d /= np.linalg.norm(d, axis=1)[:, None]
    turns = np.arccos(np.clip((d[:-1] * d[1:]).sum(1), -1.0, 1.0))
    return [(p[i + 1], t) for i, t in enumerate(turns) if t > 1e-3]


def bend_problems(c: Cable) -> list[str]:
    """What the mesh says against the route's bends: a bend under the kind's minimum, a bend not at the route's
    radius, a corner without its fillet (a fillet of radius R in a corner of turn theta has its centre
    R / cos(theta / 2) from the corner; corners whose arc is too short for a long fit are skipped, as the fan
    lead's 5 deg kink, 0.7 mm long)."""
    kind, R, out = KINDS[c.route.kind], c.route.radius_mm, []
    if not c.bends:
        return [f"{c.route.name}: no bend on the mesh"]
    for b in c.bends:
        long = b.arc_mm >= LONG_ARC_SHARE * b.radius_mm
        if b.radius_mm < kind.min_bend_radius_mm * (1 - (RADIUS_REL if long else SHORT_REL)):
            out.append(f"{c.route.name}: a {b.radius_mm:.2f} mm bend, under the {kind.min_bend_radius_mm:g} mm minimum")
        if long and abs(b.radius_mm - R) > RADIUS_REL * R:
            out.append(f"{c.route.name}: a {b.radius_mm:.2f} mm bend where the route says {R:g} mm")
    long_bends = [b for b in c.bends if b.arc_mm >= LONG_ARC_SHARE * b.radius_mm]
    for corner, turn in _corners(c.route):
        if R * turn < 2 * _span_mm(kind) + LONG_ARC_SHARE * R:
            continue
        want = R / math.cos(turn / 2)
        got = min([np.linalg.norm(b.centre - corner) for b in long_bends] + [np.inf])
        if abs(got - want) > 0.1 + RADIUS_REL * R:
            out.append(f"{c.route.name}: the corner at {np.round(corner, 1).tolist()} has no fillet centre "
                       f"{want:.2f} mm from it (nearest {got:.2f} mm)")
    return out


@pytest.mark.slow
def test_every_bend_read_off_the_mesh_is_at_the_route_s_radius_and_in_its_corner(scene):
    problems = [p for c in scene.cables.values() for p in bend_problems(c)]
    assert problems == []
    assert scene.brep.ok
    assert sum(len(c.bends) for c in scene.cables.values()) >= 25


def _harness(r: Route):
    """Two routes are one harness when they are bought as one entry and leave one point (the sync Y): stated
    here from the routes, not taken from the check."""
    return (r.catalogue, tuple(np.round(r.points[0], 3))) if r.catalogue else r.name


@pytest.mark.slow
def test_no_cable_s_inside_is_inside_a_part_or_another_cable_and_each_plug_ends_on_its_part(scene):
    """Points inside each tube (its centre line and four points at 0.6 r round it, not its surface) are in no
    part's mesh and in no other harness's cable; a cable that plugs into a part ends on it: a point 0.2 mm past
    its end face is inside that part, so only the end face touches."""
    for name, c in scene.cables.items():
        assert scene.part_hits(c) == {}, name
        pts = mc.inside_points(c.points, c.radius_mm)
        for other, o in scene.cables.items():
            if other != name and _harness(o.route) != _harness(c.route):
                assert not mc.contains(o.mesh, pts, scene.trees[f"cable {other}"]).any(), (name, other)
        caps = sorted(mc.end_caps(c.mesh), key=lambda k: np.linalg.norm(k.centre - np.asarray(c.route.points[0])))
        for end, cap, plug in zip(c.route.ends, caps, c.route.plugs):
            if plug:
                assert end in scene.parts, (name, end)
                assert mc.contains(scene.parts[end], (cap.centre + 0.2 * cap.normal)[None], scene.trees[end])[0], (name, end)
                assert not mc.contains(scene.parts[end], (cap.centre - 0.2 * cap.normal)[None], scene.trees[end])[0]
    assert scene.brep.ok


# ----------------------------------------------------------------------------- deliberate defects fail both paths
@pytest.mark.slow
def test_a_cable_through_the_wall_fails_on_the_mesh_as_on_the_b_rep(asm, scene, tmp_path):
    from cad.checks import check_cables
    i = asm.layout.case.interior
    x = next(x for x, s in asm.layout.case.lugs if s > 0 and x < -50)   # no slot beside a lug
    z = -50.0
    wall = Route("test_wall", "sync_pair", None, ("a", "b"), ((x, i.hi[1] - 10, z), (x, i.hi[1] + 20, z)),
                 KINDS["sync_pair"].min_bend_radius_mm)
    hits = scene.part_hits(_cable(wall, tmp_path))
    assert "case_lower" in hits, hits
    # the inside points in the wall: the tube's share of its 30 mm run that is in the 2.4 mm wall, five per section
    wall_mm = asm.layout.fits.wall
    assert hits["case_lower"] == pytest.approx(5 * wall_mm / mc.STEP_MM, abs=10)
    b = check_cables(asm, only=[wall])
    assert not b.ok and any(p.startswith("cable test_wall") and "case_lower" in p for p in b.details)


@pytest.mark.slow
def test_a_rig_cable_moved_into_the_side_wall_fails_on_the_mesh_as_on_the_b_rep(asm, scene, tmp_path):
    """The left USB lead moved out (+y) until its axis runs along the side wall's mid-plane beside the devkit."""
    from cad.cables import cable_report
    usb = scene.cables["usb_left"].route
    lane = max(p[1] for p in usb.points)
    dy = (asm.layout.case.interior.hi[1] + asm.layout.case.outer.hi[1]) / 2 - lane
    moved = dataclasses.replace(usb, envelopes=(), points=tuple((p[0], p[1] + dy, p[2]) for p in usb.points))
    hits = scene.part_hits(_cable(moved, tmp_path))
    assert hits.get("case_lower", 0) > 100, hits
    rep = cable_report(asm, only=[moved])
    assert any(p.startswith("cable usb_left (") and "case_lower" in p for p in rep.problems), rep.problems


@pytest.mark.slow
def test_a_twin_laid_on_a_cable_fails_on_the_mesh_as_on_the_b_rep(asm, scene, tmp_path):
    from cad.cables import cable_report
    dc = scene.cables["dc_lead"]
    twin_route = dataclasses.replace(dc.route, name="test_twin", catalogue=None, envelopes=(),
                                     points=tuple((p[0], p[1], p[2] + 2.0) for p in dc.route.points))
    twin = _cable(twin_route, tmp_path)
    inside = mc.contains(dc.mesh, mc.inside_points(twin.points, twin.radius_mm))
    assert inside.sum() >= len(twin.points)          # the points 0.6 r under the twin's axis are all in the DC lead
    rep = cable_report(asm, only=[dc.route, twin_route])
    assert any("cable dc_lead and cable test_twin overlap" in p for p in rep.problems), rep.problems


@pytest.mark.slow
def test_a_bend_at_half_the_radius_fails_on_the_mesh_as_on_the_b_rep(asm, scene, tmp_path):
    from cad.cables import path_of
    k = KINDS["dc_lead"]
    half = dataclasses.replace(scene.cables["dc_lead"].route, name="test_half", radius_mm=k.min_bend_radius_mm / 2)
    c = _cable(half, tmp_path)
    assert c.bends and all(b.radius_mm == pytest.approx(k.min_bend_radius_mm / 2, rel=RADIUS_REL) for b in c.bends)
    assert any(f"under the {k.min_bend_radius_mm:g} mm minimum" in p for p in bend_problems(c))
    assert any(f"needs at least {k.min_bend_radius_mm:g} mm" in p for p in path_of(half, k).problems)
