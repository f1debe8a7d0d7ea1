"""The tests' ray-casting broad phase (tests/cad/trimesh_rays.py) gives what testing every triangle's box gives, and
trimesh's ray caster finds the same hits through it as through a brute-force broad phase."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

trimesh = pytest.importorskip("trimesh")
from tests.cad.trimesh_rays import TriangleBoxes, ray_hits  # noqa: E402


def brute(tri: np.ndarray, box) -> np.ndarray:
    lo, hi = tri.min(axis=1), tri.max(axis=1)
    box = np.asarray(box, float)
    return np.flatnonzero(np.all(lo <= box[3:], axis=1) & np.all(hi >= box[:3], axis=1))


class Brute:
    def __init__(self, tri):
        self.tri = tri
        self.bounds = np.concatenate([tri.min(axis=(0, 1)), tri.max(axis=(0, 1))])

    def intersection(self, box):
        return brute(self.tri, box)


def _triangles(rng, n: int) -> np.ndarray:
    """Triangles of every size: specks, slivers along an axis (a flat box), and some spanning the whole scene."""
    centre = rng.uniform(-50, 50, (n, 1, 3))
    size = rng.choice([0.01, 1.0, 10.0, 120.0], size=(n, 1, 1))
    tri = centre + rng.uniform(-1, 1, (n, 3, 3)) * size
    flat = rng.uniform(size=n) < 0.2
    tri[flat, :, rng.integers(0, 3)] = tri[flat, :1, 0][:, :1]            # all three vertices on one plane
    return tri


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(0, 400), axes=st.sampled_from([(0, 1, 2), (0, 1), (2,)]))
def test_the_grid_finds_exactly_the_triangles_whose_boxes_meet_the_query(seed, n, axes):
    rng = np.random.default_rng(seed)
    tri = _triangles(rng, n)
    grid = TriangleBoxes(tri, axes)
    for _ in range(40):
        lo = rng.uniform(-200, 200, 3)
        box = np.r_[lo, lo + rng.uniform(0, 80, 3) * (rng.uniform(size=3) < 0.7)]    # some queries flat or a point
        assert np.array_equal(grid.intersection(box), brute(tri, box))
    if n:                               # a query box that just touches a triangle's box, face to face
        k = int(rng.integers(n))
        hi = tri[k].max(axis=0)
        box = np.r_[hi, hi + 5.0]
        got = grid.intersection(box)
        assert k in got and np.array_equal(got, brute(tri, box))


def test_trimesh_finds_the_same_hits_through_the_grid_as_through_every_triangle():
    mesh = trimesh.creation.icosphere(subdivisions=3, radius=20.0)
    mesh = trimesh.util.concatenate([mesh, trimesh.creation.box((30.0, 8.0, 60.0))])
    rng = np.random.default_rng(7)
    origins = rng.uniform(-30, 30, (500, 3))
    dirs = rng.normal(size=(500, 3))
    dirs /= np.linalg.norm(dirs, axis=1)[:, None]
    got = ray_hits(mesh.triangles, mesh.face_normals, origins, dirs)
    from trimesh.ray.ray_triangle import ray_triangle_id
    want = ray_triangle_id(mesh.triangles, origins, dirs, triangles_normal=mesh.face_normals,
                           tree=Brute(mesh.triangles), multiple_hits=True)
    key = lambda h: sorted(zip(h[1].tolist(), h[0].tolist()))                     # (ray, triangle) pairs
    assert len(got[0]) > 300 and key(got) == key(want)
