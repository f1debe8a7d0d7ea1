"""From X-corner candidates to a labelled grid: which candidate is corner (i, j) of the board.

1. Each candidate looks for its nearest neighbour along each of its two edge lines, both ways
   (four slots); an edge is kept only if both ends choose each other and the neighbouring spacings
   along that line agree (a missed corner would otherwise make a double step).
2. A breadth-first walk over those edges labels the candidates with lattice steps, carrying each
   corner's orientation of its two lines to the next; labels that disagree are dropped.
3. The largest labelled component becomes the board. Its labels are made right-handed (the board is
   seen from the front: never a mirrored grid) and turned, among the rotations that fit a W x H
   board, to the one whose +i steps point most to the image's right: corner (0, 0) is the board's
   top-left corner as seen in the image. A square board thus has one answer per image; a board held
   more than 45 deg from upright is reported turned (a rigid symmetry of the corner grid). A partial
   board whose two quarter-turn labellings are both within TURN_MARGIN_DEG of 45 deg as seen (the roll
   taken from both step directions, which a fisheye's edge shears apart) is refused: which side is its
   top the image cannot tell.
4. A board cut by the image edge or occluded: its offset on the board is anchored by a visible
   board edge (square centres past the last corner line stop alternating); if neither end of an
   axis is seen, the offset is ambiguous and the view is dropped rather than guessed; so is it
   when both ends look like the board's edge (one is not: a hand over the squares past a line
   looks as plain as the border). The placement is then checked against the image
   (detector.goes_on_past_edge): no corner of the grid may show on a line past the board's edge.
"""
from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import map_coordinates
from scipy.spatial import cKDTree

from ._fast import link_kernel
from .candidates import Candidates

ANGLE_TOL = np.radians(20.0)
LINE_AGREE_TOL = np.radians(25.0)
SPACING_RATIO = 1.6
K_NEIGHBOURS = 10
CLOSED_REF = 0.5    # squares past the last corner line: at least this share of the inner squares' amplitude
CLOSED_STRONG = 0.2  # ... below this share: the board ends there, whatever the other end shows
CLOSED_OUT = 0.4   # and the next 'squares' below this share of them: the board ends there


@dataclass(frozen=True)
class Grid:
    index: np.ndarray        # (m,) candidate index of each labelled corner
    ij: np.ndarray           # (m, 2) board coordinates (i across, j down)
    reason: str = ""         # why a view was dropped (empty if kept)


def _angle_diff_mod_pi(a, b):
    d = np.abs((a - b) % np.pi)
    return np.minimum(d, np.pi - d)


def link(c: Candidates) -> np.ndarray:
    """slots[p, line, side] = neighbour index or -1; side 0 is +direction of the line (numba:
    _fast.link_kernel; ``_link_python`` is the reference)."""
    n = len(c.xy)
    if n < 2:
        return -np.ones((n, 2, 2), dtype=int)
    k = min(K_NEIGHBOURS + 1, n)
    dist, nb = cKDTree(c.xy).query(c.xy, k=k)
    return link_kernel(np.ascontiguousarray(c.xy, float), np.ascontiguousarray(c.dirs, float),
                       np.ascontiguousarray(dist, float), np.ascontiguousarray(nb, np.int64),
                       float(ANGLE_TOL), float(LINE_AGREE_TOL), float(SPACING_RATIO))


def _link_python(c: Candidates) -> np.ndarray:
    """link in numpy and Python loops: the reference for _fast.link_kernel."""
    n = len(c.xy)
    slots = -np.ones((n, 2, 2), dtype=int)
    if n < 2:
        return slots
    tree = cKDTree(c.xy)
    k = min(K_NEIGHBOURS + 1, n)
    dist, nb = tree.query(c.xy, k=k)
    best = np.full((n, 2, 2), np.inf)
    for col in range(1, k):
        q = nb[:, col]
        d = c.xy[q] - c.xy
        phi = np.arctan2(d[:, 1], d[:, 0])
        for L in (0, 1):
            theta = c.dirs[:, L]
            along = _angle_diff_mod_pi(phi, theta) < ANGLE_TOL
            # the neighbour's own lines must continue this line
            agree = np.minimum(_angle_diff_mod_pi(c.dirs[q, 0], theta),
                               _angle_diff_mod_pi(c.dirs[q, 1], theta)) < LINE_AGREE_TOL
            side = (np.cos(phi - theta) < 0).astype(int)
            ok = along & agree
            for p in np.flatnonzero(ok):
                s = side[p]
                if dist[p, col] < best[p, L, s]:
                    best[p, L, s] = dist[p, col]
                    slots[p, L, s] = q[p]
    # mutual choice
    for p in range(n):
        for L in (0, 1):
            for s in (0, 1):
                q = slots[p, L, s]
                if q >= 0 and not np.any(slots[q] == p):
                    slots[p, L, s] = -1
    # spacing consistency along a line: a double step (missed corner) is twice as long as its neighbour
    length = np.where(slots >= 0, np.linalg.norm(c.xy[np.maximum(slots, 0)] - c.xy[:, None, None, :], axis=-1), np.nan)
    for p in range(n):
        for L in (0, 1):
            a, b = length[p, L]
            if np.isfinite(a) and np.isfinite(b) and max(a, b) > SPACING_RATIO * min(a, b):
                s = 0 if a > b else 1
                q = slots[p, L, s]
                slots[p, L, s] = -1
                if q >= 0:
                    slots[q][slots[q] == p] = -1
    return slots


def label(c: Candidates, slots: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """BFS labelling of the largest component: (indices, ij) with arbitrary origin and orientation."""
    n = len(c.xy)
    degree = (slots >= 0).sum(axis=(1, 2))
    seen = np.zeros(n, bool)
    best_idx, best_ij = np.zeros(0, int), np.zeros((0, 2), int)
    unit = np.stack([np.cos(c.dirs), np.sin(c.dirs)], axis=-1).tolist()   # (n, 2 lines, 2)
    sl = slots.tolist()                    # plain lists: the walk touches each a few times
    for seed in np.argsort(-degree).tolist():
        if seen[seed] or degree[seed] == 0:
            continue
        # axis_of[p, L] = global axis (0 i, 1 j) of line L; orient[p, L] = +1/-1
        axis_of = {seed: (0, 1)}
        orient = {seed: (1, 1)}
        lab = {seed: (0, 0)}
        conflict = set()
        queue = deque([seed])
        seen[seed] = True
        while queue:
            p = queue.popleft()
            for L in (0, 1):
                for s in (0, 1):
                    q = sl[p][L][s]
                    if q < 0:
                        continue
                    A = axis_of[p][L]
                    step = orient[p][L] * (1 if s == 0 else -1)
                    new = list(lab[p])
                    new[A] += step
                    new = tuple(new)
                    if q in lab:
                        if lab[q] != new:
                            conflict.add(q)
                        continue
                    # orientation at q: the line through p is L2, its side towards p is s2
                    where = [(a, b) for a in (0, 1) for b in (0, 1) if sl[q][a][b] == p]
                    if not where:
                        continue
                    L2, s2 = where[0]
                    ax = [0, 0]
                    ori = [0, 0]
                    ax[L2] = A
                    ori[L2] = -step * (1 if s2 == 0 else -1)
                    # the other line: orient along p's direction of the other axis
                    B = 1 - A
                    LB = axis_of[p].index(B)
                    o = orient[p][LB]
                    vB = (o * unit[p][LB][0], o * unit[p][LB][1])
                    uq = unit[q][1 - L2]
                    ax[1 - L2] = B
                    ori[1 - L2] = 1 if uq[0] * vB[0] + uq[1] * vB[1] >= 0 else -1
                    axis_of[q], orient[q], lab[q] = tuple(ax), tuple(ori), new
                    seen[q] = True
                    queue.append(q)
        if len(lab) - len(conflict) <= len(best_idx):
            continue                       # cannot beat the best component: skip the bookkeeping
        idx = np.array([k for k in lab if k not in conflict], int)
        ij = np.array([lab[k] for k in idx], int).reshape(-1, 2)
        # one candidate per label
        if len(ij):
            _, first, counts = np.unique(ij, axis=0, return_index=True, return_counts=True)
            dup = {tuple(ij[f]) for f, cnt in zip(first, counts) if cnt > 1}
            keep = np.array([tuple(x) not in dup for x in ij])
            idx, ij = idx[keep], ij[keep]
        if len(idx) > len(best_idx):
            best_idx, best_ij = idx, ij
    return best_idx, best_ij


def _step_vectors(xy: np.ndarray, ij: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean image displacement of a +i step and of a +j step."""
    pos = {tuple(k): p for k, p in zip(ij, xy)}
    di, dj = [], []
    for (i, j), p in pos.items():
        if (i + 1, j) in pos:
            di.append(pos[(i + 1, j)] - p)
        if (i, j + 1) in pos:
            dj.append(pos[(i, j + 1)] - p)
    zero = np.zeros(2)
    return (np.mean(di, axis=0) if di else zero), (np.mean(dj, axis=0) if dj else zero)


def right_handed(xy: np.ndarray, ij: np.ndarray) -> np.ndarray:
    """The labels with their axes swapped if the grid they make is mirrored (the board is always seen
    from the front)."""
    di, dj = _step_vectors(xy, ij)
    return ij[:, ::-1].copy() if di[0] * dj[1] - di[1] * dj[0] < 0 else ij


TRIM_EXTRA = 2            # at most this many surplus lattice lines along an axis are trimmed off
TRIM_MAX_DROPPED = 3      # ... holding at most this many corners in all (clutter, not board)


def _best_window(ij: np.ndarray, W: int, H: int) -> tuple[np.ndarray | None, int]:
    """The W x H window (in label units, ij starting at 0) holding the most corners, if it is the
    only best one and what it leaves out is a few stray corners; (offset, n dropped) or (None, n)."""
    ni, nj = ij.max(axis=0) + 1
    wi, wj = min(ni, W), min(nj, H)
    occ = np.zeros((nj, ni), int)
    occ[ij[:, 1], ij[:, 0]] = 1
    cs = np.pad(occ.cumsum(0).cumsum(1), ((1, 0), (1, 0)))
    counts = cs[wj:, wi:] - cs[:-wj, wi:] - cs[wj:, :-wi] + cs[:-wj, :-wi]      # (nj-wj+1, ni-wi+1)
    flat = np.sort(counts.ravel())[::-1]
    dropped = len(ij) - int(flat[0])
    if (len(flat) > 1 and flat[1] == flat[0]) or dropped > TRIM_MAX_DROPPED:
        return None, dropped
    oj, oi = np.unravel_index(int(np.argmax(counts)), counts.shape)
    return np.array([oi, oj]), dropped


def orient(xy: np.ndarray, ij: np.ndarray, W: int, H: int) -> tuple[np.ndarray, str]:
    """Right-handed labels, turned so +i points most to the right among those that fit W x H;
    returns (ij normalised to start at 0, reason if none fits). A grid one or two lattice lines
    larger than the board (a background corner linked to it) is trimmed to the W x H window
    holding the most corners, when that window is unique and leaves out at most a few strays;
    trimmed-off corners get ij = -1 (the caller drops them)."""
    di, dj = _step_vectors(xy, ij)
    if di[0] * dj[1] - di[1] * dj[0] < 0:          # mirrored: swap the axes
        ij = ij[:, ::-1]
        di, dj = dj, di
    fits, trims = [], []
    for k in range(4):
        ij0 = ij - ij.min(axis=0)
        ni, nj = ij0.max(axis=0) + 1
        score = di[0] / (np.linalg.norm(di) + 1e-12)
        if ni <= W and nj <= H:
            fits.append((score, ij0.copy(), _roll_deg(di, dj)))
        elif ni <= W + TRIM_EXTRA and nj <= H + TRIM_EXTRA:
            off, _ = _best_window(ij0, W, H)
            if off is not None:
                out = ij0 - off
                inside = (out[:, 0] >= 0) & (out[:, 1] >= 0) & (out[:, 0] < W) & (out[:, 1] < H)
                out[~inside] = -1
                trims.append((score, out))
        ij = np.stack([ij[:, 1], -ij[:, 0]], axis=1)   # turn 90 deg (keeps handedness)
        di, dj = dj, -di
    if fits:
        best = max(fits, key=lambda o: o[0])
        if len(ij) < W * H and _turn_ambiguous(best, fits):
            return ij, (f"partial board held about 45 deg from upright (its rows at {best[2]:+.0f} deg as seen): "
                        f"which of its sides is its top cannot be told; hold it nearer upright")
        return best[1], ""
    if trims:
        return max(trims, key=lambda o: o[0])[1], ""
    ni, nj = ij.max(axis=0) - ij.min(axis=0) + 1
    return ij, f"found a {max(ni, nj)}x{min(ni, nj)} grid of corners, larger than the {W}x{H} board"


#: a partial board's turn is taken from the image only while its rows are further than this from 45 deg as seen
TURN_MARGIN_DEG = 8.0


def _roll_deg(di: np.ndarray, dj: np.ndarray) -> float:
    """The board's roll as seen (deg, +clockwise, 0 upright): the mean direction of a +i step and of a +j step
    turned back by 90 deg. Under a fisheye's edge the two steps are far from square (seed 200 hard 10x7
    Kannala-Brandt image 027: 64 deg apart), so either alone misjudges the roll."""
    a = np.arctan2(di[1], di[0])
    b = np.arctan2(dj[1], dj[0]) - np.pi / 2
    return float(np.degrees(np.arctan2(np.sin(a) + np.sin(b), np.cos(a) + np.cos(b))))


def _turn_ambiguous(best, fits) -> bool:
    """Whether another labelling that fits the board, a quarter turn from ``best``, is about as upright: a partial
    board seen near 45 deg, whose top side the image cannot tell (complete boards are told apart by their
    shape, or are square, where a quarter turn is the corner grid's own symmetry). Two cameras of a stereo pair
    would label it differently, and a mono calibration would take it for another part of the board."""
    for other in fits:
        if other is best:
            continue
        turn = abs((other[2] - best[2] + 180.0) % 360.0 - 180.0)
        if abs(turn - 90.0) < 45.0 and min(abs(best[2]), abs(other[2])) > 45.0 - TURN_MARGIN_DEG:
            return True
    return False


def _end_state(g: np.ndarray, pos: dict, axis: int, end: int, n_other: int) -> str:
    """'closed' if the board visibly ends past the last corner line at ``end`` (0 low, 1 high) of
    ``axis``: the column of outer squares alternates but the border past it does not; 'open' if the
    squares go on alternating there (corners were missed, the board goes on); else 'unknown'."""
    H, W = g.shape
    line = 0 if end == 0 else max(k[axis] for k in pos)
    inward = 1 if end == 0 else -1
    ms, inn, ref, out = [], [], [], []
    for m in range(n_other - 1):
        def P(a, b):
            key = [0, 0]
            key[axis] = line + inward * a
            key[1 - axis] = b
            return pos.get(tuple(key))
        p0a, p1a, p0b, p1b = P(0, m), P(1, m), P(0, m + 1), P(1, m + 1)
        if p0a is None or p1a is None or p0b is None or p1b is None:
            continue
        mid = (p0a + p0b) / 2
        step = ((p0a - p1a) + (p0b - p1b)) / 2        # one square outwards
        ms.append(m)
        inn.append(mid - 0.5 * step)                  # centre of the last square inside the grid
        ref.append(mid + 0.5 * step)                  # centre of the square just past the line
        out.append(mid + 1.5 * step)                  # centre of the next square, if the board goes on
    if len(ms) < 2:
        return "unknown"
    ms, inn, ref, out = np.array(ms), np.array(inn), np.array(ref), np.array(out)
    ok = np.all((out >= 1) & (out <= [W - 2, H - 2]), axis=1) & np.all((ref >= 1) & (ref <= [W - 2, H - 2]), axis=1)
    if ok.sum() < 2:
        return "unknown"
    ms, inn, ref, out = ms[ok], inn[ok], ref[ok], out[ok]
    sgn = np.where(ms % 2 == 0, 1.0, -1.0)

    def amp(pts, sel=slice(None)):
        v = map_coordinates(g, [pts[sel, 1], pts[sel, 0]], order=1, mode="nearest")
        return abs(np.mean(sgn[sel] * (v - v.mean())))
    a_in, a_ref, a_out = amp(inn), amp(ref), amp(out)
    # the squares just past the line must be seen about as clearly as those inside; otherwise
    # (faint rim, heavy blur) nothing can be said about what lies past them
    if a_ref <= 0.2 or a_ref < CLOSED_REF * a_in:
        return "unknown"
    if a_out < CLOSED_OUT * a_ref and len(ms) >= 4:
        # a hand over part of the rim hides squares that go on, and the mean over the line then
        # looks like the board's border (seed 200 hard 7x7 033: a whole board labelled one column
        # off). The border is plain all along the line: where either half of it shows squares going
        # on, the line is not the board's end
        for part in (slice(0, len(ms) // 2), slice(len(ms) // 2, None)):
            if amp(out, part) > 0.7 * amp(ref, part):
                return "unknown"
    if a_out < CLOSED_STRONG * a_ref:
        return "closed!"
    if a_out < CLOSED_OUT * a_ref:
        return "closed"
    if a_out > 0.7 * a_ref:
        return "open"
    return "unknown"


def board_edge_seen(g: np.ndarray, xy: np.ndarray, ij: np.ndarray, axis: int, end: int) -> bool:
    """Whether the board visibly ends just past the grid's first (``end`` 0) or last (1) lattice line
    along ``axis`` (labels ``ij`` starting at 0): _end_state says 'closed'."""
    pos = {tuple(k): np.asarray(p, float) for k, p in zip(ij.tolist(), xy)}
    return _end_state(g, pos, axis, end, int(ij[:, 1 - axis].max()) + 1).startswith("closed")


def _next_line_inside(shape, pos: dict, axis: int, end: int, margin: float = 4.0) -> float:
    """Share of the next lattice line past ``end`` of ``axis`` (extrapolated from the last two
    lines) that falls inside the image (``margin`` pixels from its edges)."""
    H, W = shape
    line = 0 if end == 0 else max(k[axis] for k in pos)
    inward = 1 if end == 0 else -1
    pts = []
    for k, p in pos.items():
        if k[axis] != line:
            continue
        key = list(k)
        key[axis] = line + inward
        q = pos.get(tuple(key))
        if q is not None:
            pts.append(2 * np.asarray(p) - np.asarray(q))
    if not pts:
        return 0.0
    pts = np.array(pts)
    return float(np.mean((pts[:, 0] >= margin) & (pts[:, 1] >= margin) &
                         (pts[:, 0] <= W - 1 - margin) & (pts[:, 1] <= H - 1 - margin)))


def anchor(g: np.ndarray, xy: np.ndarray, ij: np.ndarray, W: int, H: int,
           corners_go_on=None) -> tuple[np.ndarray | None, str]:
    """Place a (possibly partial) grid on the board: add the offsets; None and a reason if unsure.
    ``corners_go_on(axis, end)`` (optional) says whether the image shows corners of this grid on the
    lattice line just past ``end`` (0 low, 1 high) of ``axis`` (labels ``ij`` as given): an 'open'
    end that shows none does not back a weak 'closed' one at the other end."""
    pos = {tuple(k): p for k, p in zip(ij, xy)}
    out = ij.copy()
    for axis, n_board in ((0, W), (1, H)):
        n_seen = ij[:, axis].max() + 1
        n_other = ij[:, 1 - axis].max() + 1
        if n_seen == n_board:
            # all corners along this axis seen. (Checking that the board ends past them too gave
            # false alarms near the image edge; a board bigger than --board is caught by orient()
            # when its extra corners are found, and by the anchoring below when they are not all.)
            continue
        lo = _end_state(g, pos, axis, 0, n_other)
        hi = _end_state(g, pos, axis, 1, n_other)
        # both ends look like the board's border with corners missing: one of them is not (a hand
        # over the squares past a line looks plain too: stereographic hard seed 11, 8x8, image 013,
        # 17 corners labelled four columns off, up to 153 px), and nothing says which
        name = "i (across)" if axis == 0 else "j (down)"
        if lo.startswith("closed") and hi.startswith("closed"):
            return None, (f"the board ends after {n_seen} corners along {name}, not {n_board}: check the board "
                          f"size (or the board is occluded across, or a hand hides one end)")
        # a weak 'closed' (the next squares faint, not gone) counts only when the other end
        # positively goes on, or the corners missing there would lie outside the image; a faint
        # last row of squares inside the image looks the same as the board's border otherwise
        for end, this, other in ((0, lo, hi), (1, hi, lo)):
            if this == "closed" and other == "open" and corners_go_on is not None \
                    and not corners_go_on(axis, 1 - end):
                # the squares past the other end 'alternate', but no corner of the grid shows on the
                # line there: the alternation is the background's (8-bit AGC: opencv8 hard seed 11
                # image 001, the stripes past the board's top edge, while its faint last row read as
                # the border: 25 corners labelled one row off, 14-19 px)
                other = "unknown"
            if this == "closed" and other != "open" and _next_line_inside(g.shape, pos, axis, 1 - end) > 0.5:
                if end == 0:
                    lo = "unknown"
                else:
                    hi = "unknown"
        lo, hi = lo.rstrip("!"), hi.rstrip("!")
        if lo == "closed" and hi != "closed":
            continue
        if hi == "closed" and lo != "closed":
            out[:, axis] += n_board - n_seen
            continue
        return None, (f"partial board: {n_seen} of {n_board} corners along {name} and neither board edge "
                      f"seen; cannot tell which corners they are")
    return out, ""
