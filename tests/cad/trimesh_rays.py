"""trimesh's own ray caster for the tests' independent mesh paths (walls, airflow, cables), without the rtree package
it normally asks for: the broad phase over the triangles' boxes in numpy, on a uniform grid."""
from __future__ import annotations

import math

import numpy as np
from trimesh.ray.ray_triangle import ray_triangle_id

#: cells along the longest side of the triangles' bounds, at most
CELLS_ALONG = 64
#: (triangle, cell) entries the grid may hold, at most: the cells are made larger until it holds no more
MAX_ENTRIES = 4_000_000


class TriangleBoxes:
    """The broad phase ``ray_triangle_id`` asks of an r-tree: ``bounds`` and ``intersection(box)``, the triangles
    (ascending indices) whose axis-aligned boxes meet a box (x0, y0, z0, x1, y1, z1), over (N, 3, 3) triangles.

    Each triangle is listed in every cell of a uniform grid that its box meets: cubes of the longest gridded side of
    the bounds over CELLS_ALONG, or larger ones where large triangles would make that more than MAX_ENTRIES entries.
    A query gathers the triangles of the cells its box meets and keeps those whose boxes meet it. The same answer as
    testing every triangle's box (tests/cad/test_trimesh_rays.py), without a pass over all of them per ray: that pass
    was most of the wall and airflow tests' time."""

    def __init__(self, tri: np.ndarray, axes: tuple = (0, 1, 2)):
        """``axes``: those the grid divides (the others are one cell): (0, 1) for rays along z, whose boxes
        are long in z and would meet a column of cells each."""
        self.lo, self.hi = tri.min(axis=1), tri.max(axis=1)
        self.bounds = np.concatenate([self.lo.min(axis=0), self.hi.max(axis=0)]) if len(tri) else np.zeros(6)
        extent = self.bounds[3:] - self.bounds[:3]
        whole = np.array([d not in axes for d in range(3)])
        self.cell = max(float(extent[~whole].max()) / CELLS_ALONG, 1e-6)
        while True:
            self.shape = np.where(whole, 1, np.floor(extent / self.cell).astype(int) + 1)    # cells per axis
            a, b = self._cell(self.lo), self._cell(self.hi)
            span = b - a + 1                                                 # (N, 3) cells each box meets per axis
            count = span.prod(axis=1)
            if count.sum() <= max(MAX_ENTRIES, 8 * len(tri)):
                break
            self.cell *= 2
        k = np.repeat(np.arange(len(tri)), count)                            # triangle of each (triangle, cell)
        j = np.arange(len(k)) - np.repeat(np.cumsum(count) - count, count)   # its place in the triangle's cells
        sy, sz = span[k, 1], span[k, 2]
        nyz = self.shape[1] * self.shape[2]
        cell = (a[k, 0] + j // (sy * sz)) * nyz + (a[k, 1] + (j // sz) % sy) * self.shape[2] + a[k, 2] + j % sz
        order = np.lexsort((k, cell))                                        # by cell, then triangle
        cell, k = cell[order], k[order]
        keys, starts = np.unique(cell, return_index=True)
        ends = np.r_[starts[1:], len(cell)]
        #: each cell's triangles (ascending), by cell key; the grid as plain numbers for the per-ray arithmetic
        self._cells = {int(q): k[s:e] for q, s, e in zip(keys, starts, ends)}
        self._grid = (tuple(map(float, self.bounds)), self.cell, tuple(map(int, self.shape)))

    def _cell(self, p: np.ndarray) -> np.ndarray:
        """The grid cell (..., 3) of points (..., 3), clipped to the grid."""
        return np.clip(np.floor((p - self.bounds[:3]) / self.cell).astype(int), 0, self.shape - 1)

    def intersection(self, box) -> np.ndarray:
        """Called once per ray by trimesh: the cells in plain Python arithmetic (the same float operations as
        :meth:`_cell`'s), numpy only for the triangles."""
        (bx0, by0, bz0, bx1, by1, bz1), cell, (nx, ny, nz) = self._grid
        x0, y0, z0, x1, y1, z1 = (float(v) for v in box)
        if not self._cells or x1 < bx0 or y1 < by0 or z1 < bz0 or x0 > bx1 or y0 > by1 or z0 > bz1:
            return np.zeros(0, int)

        def span(v0, v1, o, n):
            return (min(max(math.floor((v0 - o) / cell), 0), n - 1), min(max(math.floor((v1 - o) / cell), 0), n - 1))

        (i0, i1), (j0, j1), (k0, k1) = span(x0, x1, bx0, nx), span(y0, y1, by0, ny), span(z0, z1, bz0, nz)
        cells = self._cells
        found = [cells[q] for i in range(i0, i1 + 1) for j in range(j0, j1 + 1) for k in range(k0, k1 + 1)
                 if (q := (i * ny + j) * nz + k) in cells]
        if not found:
            return np.zeros(0, int)
        if len(found) == 1:
            c = found[0]
        else:                                                   # each triangle once, in ascending order
            mark = np.zeros(len(self.lo), bool)
            for f in found:
                mark[f] = True
            c = np.flatnonzero(mark)
        lo, hi = np.array((x0, y0, z0)), np.array((x1, y1, z1))
        return c[np.all(self.lo[c] <= hi, axis=1) & np.all(self.hi[c] >= lo, axis=1)]


def ray_hits(tri: np.ndarray, normals: np.ndarray, origins: np.ndarray, dirs: np.ndarray):
    """Every hit of rays (M, 3) from ``origins`` along ``dirs`` on triangles ``tri`` (N, 3, 3) with ``normals``
    (N, 3): (triangle index (K,), ray index (K,), location (K, 3)), trimesh's ``ray_triangle_id``."""
    return ray_triangle_id(tri, origins, dirs, triangles_normal=normals, tree=TriangleBoxes(tri), multiple_hits=True)
