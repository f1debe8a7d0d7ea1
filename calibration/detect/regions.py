"""One labelling per lattice: the regions of a labelled corner grid whose labels agree with each other,
and the corners whose labels disagree with the largest region, dropped.

The breadth-first walk that labels the linked candidates (grid.label) takes each corner's label from
the first link that reaches it. One wrong link (a diagonal or next-but-one corner accepted as a unit
step: at a stretched image rim, or beside a corner the ring tests missed) shifts every label behind
it, and the walk only notices at the corners it reaches twice. What it leaves is a grid made of
regions, each internally consistent, whose labels are off from each other by a lattice vector (an
84 x 66 marker board of 8 mm squares at 0.14 m through the Kannala-Brandt truth lens: 704 corners
right, 229 shifted by one square diagonally; after the growth 973 / 281, and the marker then labelled
the 281 wrongly).

1. Regions: three consecutive labels along a lattice line (a, b, c) whose image points make a
   straight, evenly spaced run (|x_a + x_c - 2 x_b| within LINE_TOL of the mean step) join a, b and c.
   A run across a seam between two regions is off by at least one square and joins nothing, so
   the regions are the connected components of these runs.
2. The largest region is the grid. Every other region, and every corner in no run, is checked against
   it in the image: an affine map fitted from the labels of the grid's NEAREST corners nearest to it
   (within REACH_STEPS steps) to their image points says which label sits at each of the region's
   points. A region is kept if most of its judged corners get their own label back (rounded) and it
   has at least one judged corner; otherwise it is dropped, and so is a region nothing in the grid is
   near enough to judge. The growth that follows (grow.py) then finds those corners again from
   the grid, with the grid's labels.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

LINE_TOL = 0.5          # |x_a + x_c - 2 x_b| / mean step: a straight, evenly spaced run of three
NEAREST = 8             # grid corners the affine label map is fitted to
REACH_STEPS = 4.0       # ... each within this many steps of the judged point
LABEL_TOL = 0.35        # the predicted label within this of an integer, in lattice units


def _find(parent: np.ndarray, a: int) -> int:
    while parent[a] != a:
        parent[a] = parent[parent[a]]
        a = parent[a]
    return a


def regions(xy: np.ndarray, ij: np.ndarray, tol: float = LINE_TOL) -> np.ndarray:
    """(n,) region id per corner (0 the largest region, then by size), -1 for a corner in no straight
    run of three labels."""
    n = len(xy)
    idx = {tuple(t): k for k, t in enumerate(np.asarray(ij).tolist())}
    parent = np.arange(n)
    joined = np.zeros(n, bool)
    for (i, j), b in idx.items():
        for di, dj in ((1, 0), (0, 1)):
            a, c = idx.get((i - di, j - dj)), idx.get((i + di, j + dj))
            if a is None or c is None:
                continue
            s1, s2 = xy[b] - xy[a], xy[c] - xy[b]
            mean = 0.5 * (np.hypot(*s1) + np.hypot(*s2))
            if not np.isfinite(mean) or mean <= 0 or np.hypot(*(s2 - s1)) > tol * mean:
                continue
            for p in (a, c):
                ra, rb = _find(parent, p), _find(parent, b)
                if ra != rb:
                    parent[ra] = rb
            joined[[a, b, c]] = True
    roots = np.array([_find(parent, k) for k in range(n)], int)
    out = -np.ones(n, int)
    if not joined.any():
        return out
    r, counts = np.unique(roots[joined], return_counts=True)
    order = r[np.argsort(-counts, kind="stable")]
    rank = {int(root): k for k, root in enumerate(order)}
    out[joined] = [rank[int(x)] for x in roots[joined]]
    return out


def _median_step(xy: np.ndarray, ij: np.ndarray) -> float:
    idx = {tuple(t): k for k, t in enumerate(np.asarray(ij).tolist())}
    d = [np.hypot(*(xy[idx[(i + 1, j)]] - xy[k])) for (i, j), k in idx.items() if (i + 1, j) in idx]
    d += [np.hypot(*(xy[idx[(i, j + 1)]] - xy[k])) for (i, j), k in idx.items() if (i, j + 1) in idx]
    return float(np.median(d)) if d else float("nan")


def predicted_labels(xy: np.ndarray, ij: np.ndarray, grid: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """(m, 2) label the grid (corners ``grid`` of xy / ij) puts at each image point ``pts``, from an
    affine fit to its NEAREST corners nearest the point; NaN where fewer than 4 of them lie within
    REACH_STEPS steps or they span no plane."""
    out = np.full((len(pts), 2), np.nan)
    step = _median_step(xy[grid], ij[grid])
    if len(grid) < 4 or not np.isfinite(step) or len(pts) == 0:
        return out
    k = min(NEAREST, len(grid))
    d, nb = cKDTree(xy[grid]).query(pts, k=k)
    d, nb = d.reshape(len(pts), k), nb.reshape(len(pts), k)
    for m in range(len(pts)):
        near = grid[nb[m][d[m] <= REACH_STEPS * step]]
        if len(near) < 4:
            continue
        A = np.column_stack([ij[near].astype(float), np.ones(len(near))])
        M, _, rank, _ = np.linalg.lstsq(A, xy[near], rcond=None)      # xy = [i j 1] M
        if rank < 3:
            continue
        L, t = M[:2].T, M[2]
        if abs(np.linalg.det(L)) < 1e-9:
            continue
        out[m] = np.linalg.solve(L, pts[m] - t)
    return out


def disagreeing(xy: np.ndarray, ij: np.ndarray) -> tuple[np.ndarray, int]:
    """Mask of the corners whose labels do not agree with the grid's largest region (see the module
    docstring), and how many regions beside the largest were dropped."""
    reg = regions(xy, ij)
    drop = np.zeros(len(xy), bool)
    if not np.any(reg == 0):
        return drop, 0
    grid = np.flatnonzero(reg == 0)
    others = np.flatnonzero(reg != 0)
    if len(others) == 0:
        return drop, 0
    pred = predicted_labels(xy, ij, grid, xy[others])
    judged = np.isfinite(pred[:, 0])
    agree = judged & np.all(np.abs(pred - ij[others]) <= LABEL_TOL, axis=1)
    n_dropped = 0
    for r in np.unique(reg[others]):
        sel = reg[others] == r
        if r < 0:                                   # corners in no run: each on its own
            drop[others[sel & ~agree]] = True
            continue
        if not (judged[sel].any() and agree[sel].sum() > 0.5 * judged[sel].sum()):
            drop[others[sel]] = True
            n_dropped += 1
        else:
            drop[others[sel & judged & ~agree]] = True
    return drop, n_dropped
