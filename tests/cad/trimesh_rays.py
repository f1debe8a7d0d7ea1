"""trimesh's own ray caster for the tests' independent mesh paths (walls, airflow, cables), without the rtree package
it normally asks for: the broad phase over the triangles' boxes in numpy, on a uniform grid."""
from __future__ import annotations

import numpy as np
from trimesh.ray.ray_triangle import ray_triangle_id

#: cells along the longest side of the triangles' bounds, at most
CELLS_ALONG = 64
#: (triangle, cell) entries the grid may hold, at most: the cells are made larger until it holds no more
MAX_ENTRIES = 4_000_000


class TriangleBoxes:
    """The broad phase ``ray_triangle_id`` asks of an r-tree: ``bounds`` and ``intersection(box)``, the triangles
    (ascending indices) whose axis-aligned boxes meet a box (x0, y0, z0, x1, y1, z1), over (N, 3, 3) triangles.

    Each triangle is listed in every cell of a uniform grid (cubes of the bounds' longest side over CELLS_ALONG,
    or larger ones where large triangles would make that more than MAX_ENTRIES entries) that its box meets; a query gathers the triangles of the cells its box meets and keeps those whose
    boxes meet it. The same answer as testing every triangle's box (tests/cad/test_trimesh_rays.py), without a pass
    over all of them per ray: that pass was most of the wall and airflow tests' time."""

    def __init__(self, tri: np.ndarray):
        self.lo, self.hi = tri.min(axis=1), tri.max(axis=1)
        self.bounds = np.concatenate([self.lo.min(axis=0), self.hi.max(axis=0)]) if len(tri) else np.zeros(6)
        extent = self.bounds[3:] - self.bounds[:3]
        self.cell = max(float(extent.max()) / CELLS_ALONG, 1e-6)
        while True:
            self.shape = np.floor(extent / self.cell).astype(int) + 1      # cells per axis
            a, b = self._cell(self.lo), self._cell(self.hi)
            span = b - a + 1                                                 # (N, 3) cells each box meets per axis
            count = span.prod(axis=1)
            if count.sum() <= max(MAX_ENTRIES, 8 * len(tri)):
                break
            self.cell *= 2
        k = np.repeat(np.arange(len(tri)), count)                            # triangle of each (triangle, cell)
        j = np.arange(len(k)) - np.repeat(np.cumsum(count) - count, count)   # its place in the triangle's cells
        sy, sz = span[k, 1], span[k, 2]
        cell = self._key(a[k, 0] + j // (sy * sz), a[k, 1] + (j // sz) % sy, a[k, 2] + j % sz)
        order = np.lexsort((k, cell))                                        # by cell, then triangle
        cell, self._tri = cell[order], k[order]
        self._keys, self._starts = np.unique(cell, return_index=True)
        self._ends = np.r_[self._starts[1:], len(cell)]

    def _cell(self, p: np.ndarray) -> np.ndarray:
        """The grid cell (..., 3) of points (..., 3), clipped to the grid."""
        return np.clip(np.floor((p - self.bounds[:3]) / self.cell).astype(int), 0, self.shape - 1)

    def _key(self, i, j, k):
        return (i * self.shape[1] + j) * self.shape[2] + k

    def intersection(self, box) -> np.ndarray:
        box = np.asarray(box, float)
        lo, hi = box[:3], box[3:]
        if len(self.lo) == 0 or np.any(hi < self.bounds[:3]) or np.any(lo > self.bounds[3:]):
            return np.zeros(0, int)
        a, b = self._cell(lo), self._cell(hi)
        i, j, k = np.meshgrid(*(np.arange(a[d], b[d] + 1) for d in range(3)), indexing="ij")
        keys = self._key(i.ravel(), j.ravel(), k.ravel())
        at = np.searchsorted(self._keys, keys)
        found = at[(at < len(self._keys)) & (self._keys[np.minimum(at, len(self._keys) - 1)] == keys)]
        if len(found) == 0:
            return np.zeros(0, int)
        s, n = self._starts[found], self._ends[found] - self._starts[found]
        listed = self._tri[np.repeat(s - np.cumsum(n) + n, n) + np.arange(n.sum())]     # the cells' lists, end to end
        if len(found) == 1:
            c = listed
        else:                                                   # each triangle once, in ascending order
            mark = np.zeros(len(self.lo), bool)
            mark[listed] = True
            c = np.flatnonzero(mark)
        return c[np.all(self.lo[c] <= hi, axis=1) & np.all(self.hi[c] >= lo, axis=1)]


def ray_hits(tri: np.ndarray, normals: np.ndarray, origins: np.ndarray, dirs: np.ndarray):
    """Every hit of rays (M, 3) from ``origins`` along ``dirs`` on triangles ``tri`` (N, 3, 3) with ``normals``
    (N, 3): (triangle index (K,), ray index (K,), location (K, 3)), trimesh's ``ray_triangle_id``."""
    return ray_triangle_id(tri, origins, dirs, triangles_normal=normals, tree=TriangleBoxes(tri), multiple_hits=True)
