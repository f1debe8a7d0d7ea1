"""Completing a labelled corner grid: predict each missing lattice point from its labelled
neighbours, search the saddle response there, and keep what looks like a checkerboard corner of
this grid.

The candidate linking (grid.link / grid.label) only joins corners whose own ring tests passed at
fixed radii and whose neighbours chose each other; at steep tilts, heavy blur and low contrast it
leaves holes and loses whole runs of corners. Here every missing lattice point next to the grid
gets a second, better-informed look:

* prediction: the median of line extrapolations (2a - b), midpoints of opposite neighbours and
  parallelogram completions (a + b - c) of the labelled neighbours; the local steps u (+i) and
  v (+j) come with it;
* search: the strongest saddle response within 0.3 of the smaller step of the prediction;
* check (no ring test: at steep tilts its line angles are biased by 15-20 deg): the saddle
  response at least 0.2 of the grid's median (0.1 inside the grid's bounding box); the four
  quarter-squares around the point (9 samples each, laid out along the predicted u and v)
  alternating with a checker amplitude of at
  least 0.3 of the grid's, the right checker parity, and no square weaker than 0.4 of the
  amplitude (a point past the board's last corner line has its border and the background on one
  side); the samples inside the image; a point starting a new row or column counts only if at
  least two and most of that line pass together, and not where the board visibly ends (the
  squares past the grid's last line alternate and the next ones do not) once the grid would be
  larger than the board's shorter side: that line is the board's border (a framed board's rim
  passes the square checks).
The seed grid's corners go through the same quarter-square check first (the board's rim linked in).

``lattice_outliers`` checks every corner of the final grid against its neighbours after
sub-pixel refinement: a corner that drifted (more than 0.2 of the local step from where its
neighbours put it), a label with too little support, or two labels at one image position are
dropped, never reported.
"""
from __future__ import annotations

import math

import numpy as np

from .candidates import sample

NEIGH = ((1, 0), (-1, 0), (0, 1), (0, -1))
MAX_ROUNDS = 40
WEAKEST_SQUARE = 0.4             # each square at least this share of the checker amplitude
MIN_SADDLE = 0.2                 # saddle response at least this share of the grid's median
WEAKEST_INNER = 0.2             # ... for a point inside the grid's bounding box
MIN_SADDLE_INNER = 0.1           # (0.2 lost the far, faint end of steep boards)
SEED_TOL = 0.35                  # seed labels farther than this x the step from their neighbours' lattice
SEARCH_R = 6                     # largest search radius, pixels


def _angle_diff_mod_pi(a, b):
    d = np.abs((a - b) % np.pi)
    return np.minimum(d, np.pi - d)


def _median(vals: list) -> float:
    v = sorted(vals)
    n = len(v)
    return v[n // 2] if n % 2 else 0.5 * (v[n // 2 - 1] + v[n // 2])


def _mean(vecs: list) -> tuple[float, float]:
    return sum(v[0] for v in vecs) / len(vecs), sum(v[1] for v in vecs) / len(vecs)


def predict(pos: dict, t: tuple[int, int]):
    """(position, u, v, n_predictions) of lattice point ``t`` from the labelled points in ``pos``
    ((x, y) per (i, j); t itself is not used), the first three (x, y) tuples; None without a
    prediction or a step along either axis. Plain Python on tuples: this runs a few thousand times
    per image (numba would pay more to build a typed dict than it saves)."""
    i, j = t
    px, py, us, vs = [], [], [], []
    for di, dj in NEIGH:
        a = pos.get((i - di, j - dj))
        if a is None:
            continue
        sgn = di + dj
        b = pos.get((i - 2 * di, j - 2 * dj))
        if b is not None:
            px.append(2 * a[0] - b[0]), py.append(2 * a[1] - b[1])
            (us if di else vs).append(((a[0] - b[0]) * sgn, (a[1] - b[1]) * sgn))
        if sgn > 0:
            c = pos.get((i + di, j + dj))
            if c is not None:
                px.append(0.5 * (a[0] + c[0])), py.append(0.5 * (a[1] + c[1]))
                (us if di else vs).append((0.5 * (c[0] - a[0]), 0.5 * (c[1] - a[1])))
    for si in (1, -1):
        for sj in (1, -1):
            a = pos.get((i - si, j))
            if a is None:
                continue
            b = pos.get((i, j - sj))
            if b is None:
                continue
            c = pos.get((i - si, j - sj))
            if c is None:
                continue
            px.append(a[0] + b[0] - c[0]), py.append(a[1] + b[1] - c[1])
            us.append((si * (b[0] - c[0]), si * (b[1] - c[1])))
            vs.append((sj * (a[0] - c[0]), sj * (a[1] - c[1])))
    if px and (not us or not vs):
        # a step missing (t on the grid's rim): take it from the neighbours' own steps
        for di, dj in NEIGH:
            a = (i - di, j - dj)
            if a not in pos:
                continue
            pa = pos[a]
            for (ei, ej), out in (((1, 0), us), ((0, 1), vs)):
                nk, pk = (a[0] + ei, a[1] + ej), (a[0] - ei, a[1] - ej)
                if nk != t and nk in pos:
                    out.append((pos[nk][0] - pa[0], pos[nk][1] - pa[1]))
                elif pk in pos:
                    out.append((pa[0] - pos[pk][0], pa[1] - pos[pk][1]))
    if not px or not us or not vs:
        return None
    return (_median(px), _median(py)), _mean(us), _mean(vs), len(px)


_OFF = np.array([0.2, 0.325, 0.45])
_QA, _QB = [x.ravel() for x in np.meshgrid(_OFF, _OFF)]


def _squares(g: np.ndarray, p: np.ndarray, u: np.ndarray, v: np.ndarray, ij: np.ndarray):
    """The four squares around each corner, each the mean of 9 samples over the quarter of the
    square nearest the corner (0.2-0.45 steps along u and v): (signed checker amplitude times
    (-1)^(i+j), the weakest square's share of that amplitude). On a correctly labelled grid the
    first has one sign throughout; a lattice point past the board's last corner line (its border
    and the background on one side), or in clutter, has a weak square."""
    su, sv = (1, -1, -1, 1), (1, 1, -1, -1)
    qs = []
    for a, b in zip(su, sv):
        q = p[:, None, :] + (a * _QA)[None, :, None] * u[:, None, :] + (b * _QB)[None, :, None] * v[:, None, :]
        qs.append(sample(g, q[..., 0], q[..., 1]).mean(1))
    c = np.stack(qs, 1).astype(float)
    amp = (c[:, 0] - c[:, 1] + c[:, 2] - c[:, 3]) / 4
    dev = (c - c.mean(1, keepdims=True)) * np.array([1, -1, 1, -1]) * np.sign(amp)[:, None]
    weakest = dev.min(1) / np.maximum(np.abs(amp), 1e-9)
    return amp * np.where((ij.sum(1) % 2) == 0, 1.0, -1.0), weakest


def grow(g: np.ndarray, S: np.ndarray, xy: np.ndarray, ij: np.ndarray, strength: np.ndarray,
         board: tuple[int, int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Add the missing corners next to the labelled grid (xy, ij). Returns (xy, ij, added mask).
    The grid never grows past max(W, H) + 1 lattice steps along either axis."""
    Hh, Ww = g.shape
    # labels the linking got wrong (a link to a diagonal or next-but-one corner on a steep,
    # foreshortened board shifts every label behind it) sit far from where their neighbours put
    # them; growing from them spreads the shift, so they go first (growth finds the true ones)
    bad = lattice_outliers(np.asarray(xy, float), ij, SEED_TOL)
    if int(np.sum(~bad)) >= 4:
        xy, ij = xy[~bad], ij[~bad]
    pos = {tuple(k): (float(p[0]), float(p[1])) for k, p in zip(ij.tolist(), xy)}
    lim = max(board) + 1
    # the grid's checker parity and contrast, from the seed corners; seed corners whose squares do
    # not fit (the board's rim linked in, clutter) are dropped before growing
    keys0 = list(pos)
    info = [predict(pos, t) for t in keys0]
    at = {t: x for t, x in zip(keys0, info) if x is not None}
    for k, t in enumerate(keys0):
        if info[k] is None:                 # a dangling corner: judge it with a neighbour's steps
            nb = [at[(t[0] + a, t[1] + b)] for a, b in NEIGH if (t[0] + a, t[1] + b) in at]
            if nb:
                info[k] = (pos[t], nb[0][1], nb[0][2], 0)
            else:
                del pos[t]
    have = [k for k, x in enumerate(info) if x is not None]
    if not have:
        return xy[:0], ij[:0], np.zeros(0, bool)
    P = np.array([pos[keys0[k]] for k in have])
    U = np.array([info[k][1] for k in have])
    V = np.array([info[k][2] for k in have])
    par, weakest = _squares(g, P, U, V, np.array([keys0[k] for k in have]))
    parity = 1.0 if np.sum(np.sign(par)) >= 0 else -1.0
    min_amp = 0.3 * float(np.median(np.abs(par)))
    for k, a, w in zip(have, par, weakest):
        if a * parity < min_amp or w < WEAKEST_SQUARE:
            del pos[keys0[k]]
    if len(pos) < 4:
        return xy[:0], ij[:0], np.zeros(0, bool)
    seed_keys = list(pos)
    Pk = np.rint(np.array([pos[t] for t in seed_keys])).astype(int)
    S_seed = float(np.median(S[Pk[:, 1], Pk[:, 0]]))
    tried: dict = {}
    R = SEARCH_R
    oy, ox = np.mgrid[-R:R + 1, -R:R + 1]
    oy, ox = oy.ravel(), ox.ravel()
    fresh = None
    for _ in range(MAX_ROUNDS):
        keys = np.array(list(pos))
        i0, j0 = keys.min(0)
        i1, j1 = keys.max(0)
        frontier = set()
        # only lattice points whose neighbourhood changed since the last round get a new look
        near = pos if fresh is None else {(a + x, b + y) for a, b in fresh for x in range(-2, 3)
                                          for y in range(-2, 3) if (a + x, b + y) in pos}
        for (i, j) in near:
            for di, dj in NEIGH:
                t = (i + di, j + dj)
                if t in pos or t in frontier:
                    continue
                if max(i1, t[0]) - min(i0, t[0]) + 1 > lim or max(j1, t[1]) - min(j0, t[1]) + 1 > lim:
                    continue
                frontier.add(t)
        T, PR, US, VS = [], [], [], []
        for t in frontier:
            r = predict(pos, t)
            if r is None or tried.get(t) == r[3]:
                continue
            p, u, v, m = r
            tried[t] = m
            if not (2 <= p[0] <= Ww - 3 and 2 <= p[1] <= Hh - 3):
                continue
            T.append(t), PR.append(p), US.append(u), VS.append(v)
        if not T:
            break
        fresh = []
        T, PR, US, VS = np.array(T), np.array(PR), np.array(US), np.array(VS)
        nu, nv = np.linalg.norm(US, axis=1), np.linalg.norm(VS, axis=1)
        rs = np.clip(0.3 * np.minimum(nu, nv), 1.5, R)
        # strongest saddle response in the search disc
        c = np.rint(PR).astype(int)
        X = np.clip(c[:, 0:1] + ox[None, :], 0, Ww - 1)
        Y = np.clip(c[:, 1:2] + oy[None, :], 0, Hh - 1)
        d2 = (X - PR[:, 0:1]) ** 2 + (Y - PR[:, 1:2]) ** 2
        vals = np.where(d2 <= rs[:, None] ** 2, S[Y, X], -np.inf)
        k = np.argmax(vals, axis=1)
        rows = np.arange(len(T))
        ok = np.isfinite(vals[rows, k]) & (vals[rows, k] > 0)
        loc = np.stack([X[rows, k], Y[rows, k]], 1).astype(float)
        # sub-pixel peak of S (parabola per axis) for a better-centred ring
        xi, yi = loc[:, 0].astype(int), loc[:, 1].astype(int)
        inner = (xi > 0) & (yi > 0) & (xi < Ww - 1) & (yi < Hh - 1)
        xi, yi = np.clip(xi, 1, Ww - 2), np.clip(yi, 1, Hh - 2)
        for axis, (a, b) in enumerate(((S[yi, xi - 1], S[yi, xi + 1]), (S[yi - 1, xi], S[yi + 1, xi]))):
            den = a - 2 * S[yi, xi] + b
            off = np.where(inner & (den < 0), 0.5 * (a - b) / np.where(den < 0, den, -1.0), 0.0)
            loc[:, axis] += np.clip(off, -0.5, 0.5)
        amp, weakest = _squares(g, loc, US, VS, T)
        # a point inside the labelled grid's bounding box is on the board whatever its squares look
        # like (the board is a lattice rectangle holding the grid): only there a faint square or
        # saddle is accepted
        inner_pt = (T[:, 0] >= i0) & (T[:, 0] <= i1) & (T[:, 1] >= j0) & (T[:, 1] <= j1)
        ok &= (amp * parity >= min_amp) & (weakest >= np.where(inner_pt, WEAKEST_INNER, WEAKEST_SQUARE))
        ok &= vals[rows, k] >= np.where(inner_pt, MIN_SADDLE_INNER, MIN_SADDLE) * S_seed
        # the four quarter squares sampled must lie in the image (no made-up edge pixels)
        reach = 0.5 * (np.abs(US) + np.abs(VS))
        ok &= np.all((loc - reach >= 0) & (loc + reach <= [Ww - 1, Hh - 1]), axis=1)
        # a corner that would start a new row or column beyond the grid (past the board's last
        # corner line, it would be on the board's border) counts only when at least two and most
        # of that new line's corners tried this round pass too
        out_i = (T[:, 0] < i0) | (T[:, 0] > i1)
        out_j = (T[:, 1] < j0) | (T[:, 1] > j1)
        for out, axis in ((out_i, 0), (out_j, 1)):
            for val in np.unique(T[out, axis]):
                grp = out & (T[:, axis] == val)
                n_ok = int(np.sum(ok & grp))
                if n_ok < 2 or n_ok < 0.5 * int(grp.sum()):
                    ok &= ~grp
                elif (i1 - i0, j1 - j0)[axis] + 2 > min(board) and _board_ends(g, pos, axis, val > (i1, j1)[axis]):
                    # the new line would make the grid larger than the board's shorter side, and the
                    # board visibly ends right there (its outer squares alternate, then nothing):
                    # the line is the board's border, not corners
                    ok &= ~grp
        if not ok.any():
            continue
        fresh = list(map(tuple, T[ok].tolist()))
        for t, p in zip(fresh, loc[ok].tolist()):
            pos[t] = (p[0], p[1])
    keys = list(pos)
    n0 = len(seed_keys)
    new_xy = np.array([pos[t] for t in keys])
    new_ij = np.array(keys, int)
    added = np.arange(len(keys)) >= n0
    return new_xy, new_ij, added


def _board_ends(g: np.ndarray, pos: dict, axis: int, high: bool) -> bool:
    """True if the board visibly ends past the grid's last lattice line at the high (or low) end
    of ``axis`` (grid._end_state: the squares just past it alternate, the next ones do not)."""
    from .grid import _end_state
    keys = np.array(list(pos))
    k0 = keys.min(0)
    p = {(int(i - k0[0]), int(j - k0[1])): np.asarray(v) for (i, j), v in pos.items()}
    n_other = int(keys[:, 1 - axis].max() - k0[1 - axis]) + 1
    return _end_state(g, p, axis, 1 if high else 0, n_other).startswith("closed")


def lattice_outliers(xy: np.ndarray, ij: np.ndarray, tol: float = 0.2) -> np.ndarray:
    """Mask of corners farther than ``tol`` x the local step from where their labelled neighbours
    put them, of corners with fewer than two neighbour predictions (nothing vouches for their
    label), and of pairs of labels at (nearly) one image position (one of them is mislabelled:
    both go). Repeated until nothing changes: a corner vouched for only by corners dropped here
    has lost its support."""
    bad = np.zeros(len(xy), bool)
    fin = np.flatnonzero(np.isfinite(xy[:, 0]))
    if len(fin) > 1:
        from scipy.spatial import cKDTree
        d, nb = cKDTree(xy[fin]).query(xy[fin], k=2)
        step = np.median(d[:, 1])
        bad[fin[d[:, 1] < 0.4 * step]] = True
    keys = list(map(tuple, ij.tolist()))
    pts = [tuple(p) for p in xy.tolist()]
    fin = [math.isfinite(p[0]) for p in pts]
    bad = bad.tolist()
    for _ in range(len(xy)):
        pos = {k: p for k, p, b, f in zip(keys, pts, bad, fin) if f and not b}
        new = list(bad)
        for n, (k, p) in enumerate(zip(keys, pts)):
            if bad[n] or not fin[n]:
                continue
            r = predict(pos, k)
            if r is None or r[3] < 2:
                new[n] = True             # too little support to vouch for its label
                continue
            q, u, v, _ = r
            step = min(math.sqrt(u[0] * u[0] + u[1] * u[1]), math.sqrt(v[0] * v[0] + v[1] * v[1]))
            if math.sqrt((p[0] - q[0]) ** 2 + (p[1] - q[1]) ** 2) > tol * step:
                new[n] = True
        if new == bad:
            break
        bad = new
    return np.array(bad, bool)
