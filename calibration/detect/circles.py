"""detect_circle_grid(image, board, kind): heated circle grids (calibration/targets/spec.py:
``circle-grid``, ``asymmetric-circle-grid``), as Detections in the checkerboard's form (one point per
lattice point of the W x H board, grid order, NaN where not found or absent), so the solver uses them
unchanged.

1. Blobs (:func:`find_blobs`): the destriped image, smoothed, is cut at BLOB_LEVELS thresholds
   between its median and its top; a connected component is a blob candidate when it is
   elliptical (its area within ELLIPSE_FILL of the ellipse of its second moments, axes no thinner than
   MIN_AXIS_RATIO) and does not touch the image's edge; a blob is a candidate seen at two thresholds
   or more (a group of components that holds two sizeable ones at one threshold is several blobs
   merged, :func:`_merged`, and leads no group) (hot discs on a cold board; a cooled board, cold discs, is the same with the sign turned:
   both are tried, the one whose lattice is larger wins).
2. Centres (:func:`blob_centre`): the weighted centroid of the blob, weights the intensity above a
   plane fitted to the ring just outside it, divided by the disc's own level (:func:`_disc_top`: a
   plane over its interior, so a contrast falling across the disc does not pull the centre) and
   clipped to [0, 1]; a blob
   whose ring is not flat (RING_FLAT) is dropped (a hand touches it). This is the centroid of the
   imaged disc's area, which is NOT the projection of the disc's centre under perspective or a
   fisheye: :func:`disc_centroid_bias` gives the difference for a lens and pose (docs/calibration.md,
   "Circle grids", has it measured).
3. Lattice (:func:`label_lattice`): from the blob whose four nearest neighbours make the best cross,
   a walk over the blobs predicts each neighbour from the local step (the step to the neighbour's
   own neighbour continues the line: a strong fisheye bends the grid, the steps change slowly) and
   takes the nearest blob within STEP_TOL of a step (with no line to continue, the same step one
   row beside it); a blob breaking most of the lattice cells around it is dropped (:func:`off_lattice`).
   The labels are in an arbitrary basis of the
   lattice (a foreshortened asymmetric grid's shortest step can be (0, 2)).
4. Board coordinates (:func:`place`): every integer map of the labels with determinant +1 (+2 for
   the asymmetric grid, whose discs are half of the lattice; the board is seen from the front, so
   never a mirror) that puts every blob on a disc of a W x H board, the blobs spanning it exactly,
   among the maps of least span (a shear can stretch a cut view to W x H).
   Several maps (the board's own symmetry: a symmetric grid turned 180 deg, or 90 deg when W == H;
   an asymmetric grid with H even turned 180 deg) are settled by the ORIENTATION RULE: the board's
   +i direction in the image (an affine fit of all blobs) is the first met turning counterclockwise,
   as seen, from 45 deg below the image's +x axis. So (0, 0) is the top-left disc of an upright
   board, the bottom-left one of a board turned a quarter turn either way (W != H: +i points up),
   and a square grid always gets +i within 45 deg of the image's right. A board rolled close to
   45 deg (clockwise as seen, +i pointing down-right) is where the rule flips.
   An asymmetric grid with H odd has no symmetry: its labels are the board's own whatever its roll.
5. Partial views: labelled only when the blobs span the whole board across and down (discs inside
   it covered or missed are simply absent): a circle grid has no mark that says which discs a cut
   view shows, so a view cut by the image's edge is refused with the span found. A span larger than
   --board, or a whole board smaller than it (every side of the span seen inside the image with no
   disc past it), is a wrong --board, refused with the size found.
"""
from __future__ import annotations

import itertools
import math

import cv2
import numpy as np
from scipy.spatial import cKDTree

from calibration.targets.spec import circle_present

from .candidates import normalise
from .detector import Detection, empty_detection, to_float

BLOB_LEVELS = 12          # thresholds between the image's median and its 99.95th percentile
MIN_AREA_PX = 5           # a blob's fewest pixels at a threshold
MAX_AREA_SHARE = 0.05     # ... and most, as a share of the image
ELLIPSE_FILL = (0.8, 1.15)   # area / area of the moments' ellipse
MIN_AXIS_RATIO = 0.15     # minor / major axis
MIN_LEVELS = 2            # thresholds a blob must be seen at
STEP_TOL = 0.3            # a predicted neighbour matches a blob within this share of the step
AREA_RATIO = 3.0          # neighbouring blobs' areas differ by at most this factor
MIN_CIRCLES = 6
RING_FLAT = 0.15          # the ring around a disc is flat within this share of the disc's contrast
MAX_TRANSFORM = 2         # |entries| of the integer maps tried in place()
MERGED_MIN_AREA_PX = 20   # two components this large at one threshold in one group: several blobs


# ----------------------------------------------------------------------------- blobs
def _components(h: np.ndarray, t: float, max_area: float) -> list[tuple[float, float, float]]:
    """(x, y, area) of the elliptical components of ``h > t`` (h (H, W) float32) off the image edge."""
    n, lab, stats, cent = cv2.connectedComponentsWithStats((h > t).astype(np.uint8), connectivity=8)
    H, W = h.shape
    out = []
    for k in range(1, n):
        x, y, w, hh, area = stats[k]
        if area < MIN_AREA_PX or area > max_area or x == 0 or y == 0 or x + w >= W or y + hh >= H:
            continue
        m = cv2.moments((lab[y:y + hh, x:x + w] == k).astype(np.uint8), binaryImage=True)
        cov = np.array([[m["mu20"], m["mu11"]], [m["mu11"], m["mu02"]]]) / m["m00"]
        lam = np.linalg.eigvalsh(cov)
        if lam[0] <= 0:
            continue
        fill = area / (4 * math.pi * math.sqrt(lam[0] * lam[1]))
        if not ELLIPSE_FILL[0] <= fill <= ELLIPSE_FILL[1] or math.sqrt(lam[0] / lam[1]) < MIN_AXIS_RATIO:
            continue
        out.append((x + m["m10"] / m["m00"], y + m["m01"] / m["m00"], float(area)))
    return out


def _merged(members: np.ndarray) -> bool:
    """Whether components (x, y, area, threshold) grouped around a large one are several blobs: two of
    them at one threshold, each of MERGED_MIN_AREA_PX or more (one disc is one component per threshold;
    noise may split its top into specks, never into two blobs that size). A hot patch of board joining
    discs at a low threshold can be elliptical enough to lead a group and swallow the disc next to its
    centroid (stereographic truth, "real", the 8 x 7 asymmetric grid at roll 0: disc 48)."""
    big = members[members[:, 2] >= MERGED_MIN_AREA_PX]
    return len(np.unique(big[:, 3])) < len(big)


def find_blobs(h: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Blobs brighter than their surround in ``h`` (H, W) float32: (centres (n, 2) px, areas (n,) px,
    thresholds (n,): the middle one each blob was seen at)."""
    lo, hi = np.percentile(h, [50.0, 99.95])
    if hi <= lo:
        return np.zeros((0, 2)), np.zeros(0), np.zeros(0)
    max_area = MAX_AREA_SHARE * h.size
    found = []
    for t in lo + (hi - lo) * (np.arange(BLOB_LEVELS) + 0.5) / BLOB_LEVELS:
        found.extend((x, y, a, t) for x, y, a in _components(h, float(t), max_area))
    if not found:
        return np.zeros((0, 2)), np.zeros(0), np.zeros(0)
    arr = np.array(found)
    tree = cKDTree(arr[:, :2])
    group = -np.ones(len(arr), int)
    out = []
    for k in np.argsort(-arr[:, 2]):         # largest first: the group takes the components inside it
        if group[k] >= 0:
            continue
        r = max(1.5, 0.5 * math.sqrt(arr[k, 2] / math.pi))
        members = [m for m in tree.query_ball_point(arr[k, :2], r) if group[m] < 0]
        if _merged(arr[members]):
            group[k] = -2            # several blobs merged at a low threshold: not one; its parts stay free
            continue
        group[members] = len(out)
        levels = sorted(set(arr[members, 3].tolist()))
        if len(levels) >= MIN_LEVELS:
            mid = levels[len(levels) // 2]
            best = min(members, key=lambda m: (abs(arr[m, 3] - mid), -arr[m, 2]))
            out.append(arr[best])
    if not out:
        return np.zeros((0, 2)), np.zeros(0), np.zeros(0)
    out = np.array(out)
    return out[:, :2], out[:, 2], out[:, 3]


def blob_centre(h: np.ndarray, xy: np.ndarray, area: float, t: float) -> np.ndarray:
    """(2,) the weighted centroid of the blob of ``h`` (H, W) near ``xy`` (2,) seen at threshold ``t``
    with ``area`` px there (module docstring, step 2); NaN when it cannot be measured."""
    H, W = h.shape
    r = math.sqrt(area / math.pi)
    d = max(2, int(round(0.3 * r)))
    half = int(math.ceil(r * 1.6)) + 2 * d + 2
    x0, y0 = int(round(xy[0])) - half, int(round(xy[1])) - half
    if x0 < 0 or y0 < 0 or x0 + 2 * half + 1 > W or y0 + 2 * half + 1 > H:
        return np.full(2, np.nan)
    win = h[y0:y0 + 2 * half + 1, x0:x0 + 2 * half + 1]
    n, lab = cv2.connectedComponents((win > t).astype(np.uint8), connectivity=8)
    k = lab[int(round(xy[1])) - y0, int(round(xy[0])) - x0]
    if k == 0:
        return np.full(2, np.nan)
    comp = (lab == k).astype(np.uint8)
    region = cv2.dilate(comp, np.ones((2 * d + 1, 2 * d + 1), np.uint8)) > 0
    outer = cv2.dilate(comp, np.ones((4 * d + 1, 4 * d + 1), np.uint8)) > 0
    ring = outer & ~region
    if ring.sum() < 6:
        return np.full(2, np.nan)
    ys, xs = np.mgrid[0:win.shape[0], 0:win.shape[1]]
    # the board around the disc as a plane (heater falloff, a reflection: a slope across the disc)
    A = np.column_stack([xs[ring], ys[ring], np.ones(int(ring.sum()))]).astype(float)
    plane, *_ = np.linalg.lstsq(A, win[ring].astype(float), rcond=None)
    bg = plane[0] * xs + plane[1] * ys + plane[2]
    top = win - bg
    fg = float(np.percentile(top[comp > 0], 90))
    resid = win[ring] - bg[ring]
    if fg <= 0 or float(np.percentile(np.abs(resid), 90)) > RING_FLAT * fg:
        return np.full(2, np.nan)          # something warm or cold touches the disc (a hand)
    w = np.clip(top / _disc_top(top, comp, d, xs, ys, fg), 0.0, 1.0) * region
    s = float(w.sum())
    return np.array([x0 + float((w * xs).sum()) / s, y0 + float((w * ys).sum()) / s])


def _disc_top(top: np.ndarray, comp: np.ndarray, d: int, xs: np.ndarray, ys: np.ndarray, fg: float):
    """The disc's own level over the window, what a weight of 1 is: a plane fitted to the disc's interior
    (the blob eroded by ``d``), scaled so its mean there is ``fg``; ``fg`` itself where the interior is
    too small. A contrast that falls across the disc (vignetting, the warm housing at the image's
    corners, the heater's falloff, gain non-uniformity) weights its dimmer side's rim less under one
    flat scale and pulls the centroid towards the brighter side: inwards, growing with the field angle
    (stereographic truth, "real": -0.026 px radially at 35-45 deg, -0.042 at 45-60, after the
    centroid bias; ~0 with those effects off)."""
    inner = cv2.erode(comp, np.ones((2 * d + 1, 2 * d + 1), np.uint8)) > 0
    if inner.sum() < 6:
        return fg
    A = np.column_stack([xs[inner], ys[inner], np.ones(int(inner.sum()))]).astype(float)
    plane, *_ = np.linalg.lstsq(A, top[inner].astype(float), rcond=None)
    lvl = plane[0] * xs + plane[1] * ys + plane[2]
    mean = float(lvl[inner].mean())
    if mean <= 0:
        return fg
    return np.maximum(lvl * (fg / mean), 0.5 * fg)


# ----------------------------------------------------------------------------- lattice
def _seed_basis(xy: np.ndarray, p: int, nb: np.ndarray) -> tuple[np.ndarray, np.ndarray, float] | None:
    """(u, v, score) at blob ``p``: the step to its nearest neighbour and the next one across it, when
    both are matched the other way too (a cross of four neighbours); None otherwise."""
    steps = xy[nb] - xy[p]
    u = steps[0]
    lu = np.linalg.norm(u)
    best = None
    for s in steps[1:]:
        ls = np.linalg.norm(s)
        c = abs(float(u @ s)) / (lu * ls)
        if c < math.cos(math.radians(35.0)) and ls < 3.5 * lu:
            best = s
            break
    if best is None:
        return None
    err = 0.0
    for step in (-u, -best):
        e = np.min(np.linalg.norm(xy[nb] - (xy[p] + step), axis=1)) / np.linalg.norm(step)
        if e > STEP_TOL:
            return None
        err += e
    return u, best, err


def label_lattice(xy: np.ndarray, areas: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Blobs ``xy`` (n, 2) linked into the largest lattice: (indices (m,), labels (m, 2) int in an
    arbitrary basis and origin; right-handed in the image: the basis (a, b) turns like x to y)."""
    n = len(xy)
    if n < 5:
        return np.zeros(0, int), np.zeros((0, 2), int)
    tree = cKDTree(xy)
    _, nbs = tree.query(xy, k=min(9, n))
    seeds = []
    for p in range(n):
        sb = _seed_basis(xy, p, nbs[p, 1:])
        if sb is not None:
            seeds.append((sb[2], p, sb[0], sb[1]))
    seeds.sort(key=lambda s: s[0])
    best_idx, best_lab = np.zeros(0, int), np.zeros((0, 2), int)
    used = np.zeros(n, bool)
    for _, p, u, v in seeds[:12]:
        if used[p]:
            continue
        if u[0] * v[1] - u[1] * v[0] < 0:
            v = -v
        idx, lab = _walk(xy, areas, tree, p, u, v)
        used[idx] = True
        if len(idx) > len(best_idx):
            best_idx, best_lab = idx, lab
    return best_idx, best_lab


def _walk(xy, areas, tree, seed: int, u: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Breadth-first labelling from ``seed`` with its steps u, v (2,) image px."""
    lab = {seed: (0, 0)}
    at = {(0, 0): seed}
    step = {seed: (u, v)}
    queue = [seed]
    dirs = ((1, 0), (-1, 0), (0, 1), (0, -1))
    while queue:
        p = queue.pop(0)
        a, b = lab[p]
        su, sv = step[p]
        for da, db in dirs:
            key = (a + da, b + db)
            if key in at:
                continue
            back = at.get((a - da, b - db))
            s = da * su + db * sv
            if back is not None:             # continue the line: the last step, bent as it bends
                s = xy[p] - xy[back]
            else:                            # or the same step beside it (a step carried from far off is
                for o in (1, -1):            # not this one under a strong fisheye)
                    n1, n2 = at.get((a + o * db, b + o * da)), at.get((a + o * db + da, b + o * da + db))
                    if n1 is not None and n2 is not None:
                        s = xy[n2] - xy[n1]
                        break
            target = xy[p] + s
            d, q = tree.query(target)
            if d > STEP_TOL * np.linalg.norm(s) or q in lab:
                continue
            if max(areas[q], areas[p]) > AREA_RATIO * min(areas[q], areas[p]):
                continue
            new = xy[q] - xy[p]
            nu, nv = (da * new, sv) if da else (su, db * new)
            lab[q], at[key], step[q] = key, q, (nu, nv)
            queue.append(q)
    idx = np.array(list(lab), int)
    labels = np.array([lab[k] for k in idx], int)
    keep = ~off_lattice(xy[idx], labels) if len(idx) else np.zeros(0, bool)
    return idx[keep], labels[keep]


def off_lattice(xy: np.ndarray, labels: np.ndarray, tol: float = 0.25) -> np.ndarray:
    """(m,) bool: blobs ``xy`` (m, 2) at ``labels`` (m, 2) that break most of the lattice cells they
    are a corner of (a cell's two opposite steps differing by more than ``tol`` of the step; under a
    fisheye neighbouring steps differ by a few percent, a blob one place off by a whole step)."""
    at = {tuple(t): k for k, t in enumerate(labels.tolist())}
    bad = np.zeros(len(xy))
    total = np.zeros(len(xy))
    for (a, b), k00 in at.items():
        k10, k01, k11 = at.get((a + 1, b)), at.get((a, b + 1)), at.get((a + 1, b + 1))
        if k10 is None or k01 is None or k11 is None:
            continue
        cell = [k00, k10, k01, k11]
        d1, d2 = xy[k10] - xy[k00], xy[k11] - xy[k01]
        e1, e2 = xy[k01] - xy[k00], xy[k11] - xy[k10]
        broken = (np.linalg.norm(d1 - d2) > tol * np.linalg.norm(d1)
                  or np.linalg.norm(e1 - e2) > tol * np.linalg.norm(e1))
        total[cell] += 1
        bad[cell] += broken
    return (bad >= 1) & (bad > total / 2)


# ----------------------------------------------------------------------------- board coordinates
def _maps(det: int):
    """Integer 2x2 maps with entries within MAX_TRANSFORM and determinant ``det``."""
    r = range(-MAX_TRANSFORM, MAX_TRANSFORM + 1)
    for m in itertools.product(r, repeat=4):
        if m[0] * m[3] - m[1] * m[2] == det:
            yield np.array(m, int).reshape(2, 2)


def _visual_angle(ij: np.ndarray, xy: np.ndarray) -> float:
    """Degrees, counterclockwise as seen, of the board's +i direction in the image (an affine fit)."""
    A = np.column_stack([ij.astype(float), np.ones(len(ij))])
    coef, *_ = np.linalg.lstsq(A, xy, rcond=None)
    di = coef[0]
    return math.degrees(math.atan2(-di[1], di[0]))


def place(labels: np.ndarray, xy: np.ndarray, kind: str,
          board: tuple[int, int]) -> tuple[np.ndarray | None, str]:
    """Board coordinates (m, 2) of lattice ``labels`` (m, 2) (blobs at ``xy`` (m, 2)), or (None, why)
    (module docstring, steps 4 and 5)."""
    W, H = int(board[0]), int(board[1])
    asym = kind == "asymmetric-circle-grid"
    fits, spans = [], []
    for M in _maps(2 if asym else 1):
        if asym and np.any((M[0] + M[1]) % 2):          # both basis steps must join discs
            continue
        ij = labels @ M.T
        if asym:
            ij = ij - ij.min(axis=0)
            if np.any((ij[:, 0] + ij[:, 1]) % 2):        # discs sit where i + j is even
                ij[:, 0] += 1
        else:
            ij = ij - ij.min(axis=0)
        span = ij.max(axis=0) + 1
        spans.append((int(span[0] * span[1]), tuple(int(s) for s in span)))
        if tuple(span) == (W, H) and np.all(circle_present(kind, (W, H))[ij[:, 1] * W + ij[:, 0]]):
            fits.append((spans[-1][0], ij))
    # the lattice's own axes give the smallest span; a shear of a cut view can stretch it to W x H
    least = min(spans)[0]
    fits = [ij for a, ij in fits if a == least]
    if fits:
        if len({tuple(map(tuple, f.tolist())) for f in fits}) < len(fits):
            fits = list({tuple(map(tuple, f.tolist())): f for f in fits}.values())
        ang = [(_visual_angle(f, xy) + 45.0) % 360.0 for f in fits]
        return fits[int(np.argmin(ang))], ""
    span = _as_board(min(spans)[1], W >= H, asym)
    name = "discs" if not asym else "lattice points"
    if (span[0] > W or span[1] > H) and (span[0] > H or span[1] > W):
        return None, (f"found {len(labels)} circles spanning {span[0]}x{span[1]} {name}: the board is larger "
                      f"than {W}x{H}; check --board")
    return None, (f"found {len(labels)} circles spanning {span[0]}x{span[1]} {name} of the {W}x{H} grid: a "
                  f"partial view (cut by the image's edge or covered) is labelled only when it spans the whole "
                  f"board, or the board is smaller than --board")


def _as_board(span: tuple[int, int], wide: bool, asym: bool) -> tuple[int, int]:
    """A span found, written the way --board is: the longer side first when ``wide`` (W >= H), and
    for an asymmetric grid its even side first (its lattice columns) where it has one."""
    a, b = sorted(span, reverse=wide)
    if asym and a % 2 and not b % 2:
        a, b = b, a
    return a, b


# ----------------------------------------------------------------------------- detection
def _grid(h: np.ndarray):
    """(centres (m, 2), labels (m, 2), blob areas (m,), thresholds (m,)) of the largest lattice of
    bright blobs in ``h``."""
    xy, areas, levels = find_blobs(h)
    idx, lab = label_lattice(xy, areas)
    return xy[idx], lab, areas[idx], levels[idx]


def detect_circle_grid(image: np.ndarray, board: tuple[int, int], kind: str = "circle-grid") -> Detection:
    """The W x H circle grid (``kind``) in a thermal image: centres in grid order as a Detection
    (NaN where not found and where the lattice has no disc); the origin and orientation rules are
    the module docstring's."""
    W, H = int(board[0]), int(board[1])
    present = circle_present(kind, (W, H))
    f = normalise(to_float(image))
    if float(f.max() - f.min()) <= 0:
        return empty_detection((W, H), "the image is flat (every pixel the same)")
    g = cv2.GaussianBlur(f, (0, 0), 0.7)
    best = None
    for sign in (1.0, -1.0):
        h = (sign * g).astype(np.float32)
        xy, lab, areas, levels = _grid(h)
        if best is None or len(xy) > len(best[1]):
            best = (h, xy, lab, areas, levels)
    h, xy, lab, areas, levels = best
    if len(xy) < MIN_CIRCLES:
        return empty_detection((W, H), f"no grid of circles found ({len(xy)} in the largest lattice)")
    ij, why = place(lab, xy, kind, (W, H))
    if ij is None:
        return empty_detection((W, H), why, len(xy))
    centres = np.array([blob_centre(h, p, a, t) for p, a, t in zip(xy, areas, levels)])
    ok = np.isfinite(centres[:, 0])
    corners = np.full((W * H, 2), np.nan)
    level = -np.ones(W * H, int)
    k = ij[ok, 1] * W + ij[ok, 0]
    corners[k] = centres[ok]
    level[k] = 0
    corners[~present] = np.nan
    level[~present] = -1
    return Detection((W, H), corners, level, "", len(xy), extra={"radius_px": np.sqrt(areas[ok] / math.pi)})


# ----------------------------------------------------------------------------- the centroid's bias
def disc_centroid_bias(project, R: np.ndarray, t: np.ndarray, centres_m: np.ndarray, radius_m: float,
                       n_rim: int = 128) -> np.ndarray:
    """(n, 2) px: where the imaged disc's area centroid lies minus where its centre projects, for discs
    of ``radius_m`` centred at board points ``centres_m`` (n, 3) (z = 0), the board at pose R (3, 3),
    t (3,) (board -> camera), through ``project`` (points (..., 3) -> pixels (..., 2)). The rim is
    projected at ``n_rim`` points and the polygon's centroid taken (the shoelace formula). Subtract it
    from a measured centroid to get the centre's projection (the correction a solver iterates with its
    current lens and poses)."""
    a = 2 * np.pi * np.arange(n_rim) / n_rim
    ring = np.stack([np.cos(a), np.sin(a), np.zeros(n_rim)], axis=1) * radius_m
    rim = (np.asarray(centres_m, float)[:, None, :] + ring[None]) @ np.asarray(R, float).T + np.asarray(t, float)
    q = np.asarray(project(rim))
    c = np.asarray(project(np.asarray(centres_m, float) @ np.asarray(R, float).T + np.asarray(t, float)))
    x, y = q[..., 0] - c[:, None, 0], q[..., 1] - c[:, None, 1]
    xn, yn = np.roll(x, -1, axis=1), np.roll(y, -1, axis=1)
    cross = x * yn - xn * y
    area = cross.sum(axis=1) / 2
    cx = ((x + xn) * cross).sum(axis=1) / (6 * area)
    cy = ((y + yn) * cross).sum(axis=1) / (6 * area)
    return np.stack([cx, cy], axis=1)
