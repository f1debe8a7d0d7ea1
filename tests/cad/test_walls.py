"""The wall-thickness check (cad/walls.py) against solids with known thin places, and an independent
path: the exported STL read by trimesh, rays cast from every triangle's centroid along its inward
normal (``trimesh.ray.ray_triangle``), which must find the same thin places."""
from __future__ import annotations

import math

import cadquery as cq
import numpy as np
import pytest

from cad import walls

trimesh = pytest.importorskip("trimesh")
from tests.cad.trimesh_rays import ray_hits  # noqa: E402

#: the mesh path and the B-rep path agree on a flat wall's thickness within this (mm): the STL's
#: vertices lie on the exact faces, so a plane-to-plane ray differs only by rounding
FLAT_TOL_MM = 0.01
#: ... and on where a thin place is within this (mm): a mesh centroid is not the B-rep's sample point
PLACE_TOL_MM = 3.0
#: a mesh edge sharper than this (rad) is a feature edge (the export's angular tolerance is 0.2 rad)
SHARP_RAD = 0.35


@pytest.fixture(scope="module")
def printer(rig):
    p = rig.desc.printing.printer
    return p.nozzle_mm * p.min_wall_nozzles, p.nozzle_mm / 2     # the minimum wall, the edge inset


def _distance_to_segments(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    out = np.full(len(p), np.inf)
    ab = b - a
    ll = np.maximum((ab * ab).sum(axis=1), 1e-12)
    for i in range(0, len(p), 256):
        q = p[i:i + 256, None, :]
        t = np.clip(((q - a) * ab).sum(axis=2) / ll, 0.0, 1.0)
        out[i:i + 256] = np.linalg.norm(q - (a + t[..., None] * ab), axis=2).min(axis=1)
    return out


def _kept(mesh, edge_inset: float) -> np.ndarray:
    """Triangles whose centroid is at least ``edge_inset`` from a sharp mesh edge (the B-rep path reads
    near an edge that far inside the face too)."""
    c = mesh.triangles_center
    sharp = mesh.face_adjacency_angles > SHARP_RAD
    seg = mesh.vertices[mesh.face_adjacency_edges[sharp]]
    return _distance_to_segments(c, seg[:, 0], seg[:, 1]) >= edge_inset if len(seg) else np.ones(len(c), bool)


def mesh_thickness(mesh, edge_inset: float) -> tuple[np.ndarray, np.ndarray]:
    """(centroids, thickness) of the triangles :func:`_kept` keeps, by trimesh's ray caster."""
    tri, n, c = mesh.triangles, mesh.face_normals, mesh.triangles_center
    keep = _kept(mesh, edge_inset)
    origins, dirs = c[keep] - n[keep] * 1e-4, -n[keep]
    _, ray, loc = ray_hits(tri, n, origins, dirs)
    d = ((loc - origins[ray]) * dirs[ray]).sum(axis=1)
    t = np.full(len(origins), np.inf)
    ok = d > 1e-6
    np.minimum.at(t, ray[ok], d[ok] + 1e-4)
    return c[keep], t


def stl_of(shape: cq.Shape, path) -> object:
    cq.exporters.export(shape, str(path), "STL", tolerance=0.05, angularTolerance=0.2)
    return trimesh.load(str(path), process=False)


def lid_lug(spot_face: bool) -> cq.Shape:
    """The lid's split lug as it was: a 4 mm block on a wall, a 45 deg gusset above it and the screw
    head's 6.3 mm counterbore through the gusset; ``spot_face``: the gusset cut away outboard of the
    screw's axis above the head, as the case now has it."""
    wall = cq.Workplane().box(12, 2.4, 20, centered=(True, False, False)).translate((0, -2.4, 0))
    prof = [(-0.5, 0), (10, 0), (10, 4), (0, 14), (-0.5, 14)]
    lug = cq.Workplane("YZ", origin=(-6, 0, 0)).polyline(prof).close().extrude(12)
    s = wall.union(lug).cut(cq.Workplane().circle(3.15).extrude(11).translate((0, 5.25, 4)))
    if spot_face:
        s = s.cut(cq.Workplane().box(12.02, 5.0, 11, centered=(True, False, False)).translate((0, 5.25, 4)))
    return s.val()


def hollow_box(side_wall: float) -> cq.Shape:
    """A 30 x 30 x 20 mm box, 2 mm walls, one side wall (+x) ``side_wall`` thick."""
    outer = cq.Workplane().box(30, 30, 20)
    inner = cq.Workplane().box(30 - 2 - side_wall, 26, 16).translate(((side_wall - 2) / -2, 0, 0))
    return outer.cut(inner).val()


def test_the_old_lid_lug_has_a_sliver_at_its_counterbore_and_the_spot_face_removes_it(printer):
    need, inset = printer
    best, places = walls.thin_places(lid_lug(False), below=need, edge_inset=inset)
    assert places and best.thickness < need
    # on the counterbore's outboard side, where it leaves the 45 deg gusset (4 < z < 6, y beyond the bore)
    x, y, z = best.point
    assert 5.25 + 1.5 < y <= 10.0 and 4.0 <= z <= 6.0 + 1e-6
    best, places = walls.thin_places(lid_lug(True), below=need, edge_inset=inset)
    assert not places and best.thickness >= need


def test_a_deliberately_thin_wall_fails_and_is_located(printer):
    need, inset = printer
    best, places = walls.thin_places(hollow_box(0.5), below=need, edge_inset=inset)
    assert best.thickness == pytest.approx(0.5, abs=1e-3)
    # on the thin wall's faces (x from 14.5 to 15), nowhere else
    assert places and all(14.5 - 1e-6 <= p.point[0] <= 15.0 + 1e-6 for p in places)
    best, places = walls.thin_places(hollow_box(need + 0.2), below=need, edge_inset=inset)
    assert not places and best.thickness == pytest.approx(need + 0.2, abs=1e-3)


@pytest.mark.slow
@pytest.mark.parametrize("solid", ["thin_wall", "old_lug", "new_lug"])
def test_trimesh_finds_the_same_thin_places(solid, printer, tmp_path):
    need, inset = printer
    shape = {"thin_wall": lambda: hollow_box(0.5), "old_lug": lambda: lid_lug(False),
             "new_lug": lambda: lid_lug(True)}[solid]()
    best, places = walls.thin_places(shape, below=need, edge_inset=inset)
    readings, _ = walls.wall_readings(shape, edge_inset=inset, refine_below=need)
    brep_thin = np.array([w.point for w in readings if w.thickness < need]).reshape(-1, 3)
    mesh = stl_of(shape, tmp_path / "s.stl")
    pts, t = mesh_thickness(mesh, inset)
    thin = t < need
    assert bool(thin.any()) == bool(places)
    if solid == "thin_wall":
        assert t.min() == pytest.approx(best.thickness, abs=FLAT_TOL_MM)
    # every thin place the B-rep reports lies on (within the tolerance of) a triangle the mesh finds thin,
    # and every thin triangle's centroid is near a thin B-rep reading
    tri = mesh.triangles[_kept(mesh, inset)][thin]
    for p in places:
        lo, hi = tri.min(axis=1) - PLACE_TOL_MM, tri.max(axis=1) + PLACE_TOL_MM
        assert np.any(np.all((lo <= p.point) & (np.asarray(p.point) <= hi), axis=1)), p.line()
    for q in pts[thin]:
        assert np.linalg.norm(brep_thin - q, axis=1).min() <= PLACE_TOL_MM, q


@pytest.mark.slow
def test_the_default_rig_passes_and_trimesh_agrees_on_the_exported_stls(asm, results, printer, tmp_path):
    from cad.export import write_printed
    need, inset = printer
    r = results["minimum wall"]
    assert r.ok, r.details
    for pid in ("case_lid", "case_lower"):
        assert r.data[pid]["thinnest_mm"] >= need and not r.data[pid]["thin"]
    paths = write_printed(asm, tmp_path, 0.1, 0.2, {"STL"})
    for path in paths:
        if path.stem not in ("case_lid", "case_lower"):
            continue
        _, t = mesh_thickness(trimesh.load(str(path), process=False), inset)
        # the mesh finds no wall the B-rep missed (its facets sit within the 0.1 mm chord tolerance)
        assert t.min() >= need - 0.1, (path.stem, t.min())


def test_the_check_fails_a_part_with_a_thin_wall(rig, printer):
    """The check itself, not only the measure: a printed part with a 0.5 mm wall fails it, named with
    its place, and the same part with a wall just over the minimum passes."""
    from types import SimpleNamespace
    from cad import checks
    need, _ = printer
    for wall, ok in ((0.5, False), (need + 0.2, True)):
        part = SimpleNamespace(category="printed", local_shape=lambda cache, w=wall: hollow_box(w))
        r = checks.check_min_wall(SimpleNamespace(rig=rig, cache=None, printed=lambda p=part: {"test_box": p}))
        assert r.ok is ok
        if not ok:
            assert any(d.startswith("test_box: 0.50 mm at (") for d in r.details), r.details
            # located on the thin wall (x from 14.5 to 15 mm)
            assert r.data["test_box"]["thin"] and all(14.5 - 1e-6 <= pt[0] <= 15.0 + 1e-6
                                                      for _, pt in r.data["test_box"]["thin"])
