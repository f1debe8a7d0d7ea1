"""trimesh's own ray caster for the tests' independent mesh paths (walls, airflow), without the rtree package
it normally asks for: the broad phase over the triangles' boxes in numpy."""
from __future__ import annotations

import numpy as np
from trimesh.ray.ray_triangle import ray_triangle_id


class TriangleBoxes:
    """The broad phase ``ray_triangle_id`` asks of an r-tree: ``bounds`` and ``intersection(box)`` over the
    triangles' (N, 3, 3) axis-aligned boxes."""

    def __init__(self, tri: np.ndarray):
        self.lo, self.hi = tri.min(axis=1), tri.max(axis=1)
        self.bounds = np.concatenate([self.lo.min(axis=0), self.hi.max(axis=0)])

    def intersection(self, b):
        b = np.asarray(b)
        return np.flatnonzero(np.all(self.lo <= b[3:], axis=1) & np.all(self.hi >= b[:3], axis=1))


def ray_hits(tri: np.ndarray, normals: np.ndarray, origins: np.ndarray, dirs: np.ndarray):
    """Every hit of rays (M, 3) from ``origins`` along ``dirs`` on triangles ``tri`` (N, 3, 3) with ``normals``
    (N, 3): (triangle index (K,), ray index (K,), location (K, 3)), trimesh's ``ray_triangle_id``."""
    return ray_triangle_id(tri, origins, dirs, triangles_normal=normals, tree=TriangleBoxes(tri), multiple_hits=True)
