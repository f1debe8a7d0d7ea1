"""detect_marker_board(image, board=(W, H)): the checkerboard with a central marker
(calibration/targets/spec.py), labelled by its marker instead of its edges.

1. The lattice as for a plain checkerboard (detector.find_lattice), made right-handed (the board is
   seen from the front).
2. The marker: a missing lattice point with at least MIN_RING of the 16 labels two steps around it
   found (the marker's centre has no corner; its rim corners are sometimes linked in).
   Through a homography fitted to those ring corners, the four quarters of the hole and the squares
   just outside it are sampled on the destriped image. The marker is the hole where three quarters
   are alike (within QUIET of the checker amplitude) and at the board's mean temperature (within
   MID_BAND of it: neither square colour) and one, the dot, stands out from them by at least
   DOT_CONTRAST of the amplitude, on the side opposite to the two squares that share an edge with
   its quarter (on the board those have the other colour). More than one such hole, or none: the
   view is refused with the reason.
3. Board coordinates: the lattice turned (a rotation, never a mirror) so the dot's quarter is the
   marker's top-left one, and shifted so the hole's centre is corner (mi, mj). Every view that shows
   the marker is labelled, whether or not any board edge is in it.
4. A wrong --board is refused with the size found: a label outside the W x H board, or a board edge
   seen (grid._end_state) at a line that is not the board's first or last.
5. Corners that end a lattice line with a step unlike the line's (bent_line_ends) are dropped.
6. Then refinement, checks and completion as for the checkerboard (detector.finish), never
   reporting the marker's own 3 x 3 corners.
"""
from __future__ import annotations

import cv2
import numpy as np

from calibration.targets import marker_block, marker_centre

from .candidates import sample
from .detector import MIN_CORNERS, Detection, empty_detection, find_lattice, finish
from .grid import board_edge_seen, right_handed

MIN_RING = 8            # of the 16 lattice points around the marker's 3 x 3 block
QUIET = 0.2             # the three plain quarters agree within this share of the checker amplitude
MID_BAND = 0.3          # ... and sit within this share of it from the squares' mean
DOT_CONTRAST = 0.3      # the dot stands out from them by at least this share of the amplitude (a full
                        # dot: 0.5, it has one square colour, the plain quarters the mean of both)
PATCH = 0.2             # a square's value: the mean of 9 samples within +-0.2 squares of its centre
DOT_PATCH = 0.1         # ... +-0.1 for the marker's quarters (the dot's radius is 0.3 squares)
STEP_RATIO = 1.3        # consecutive steps along a lattice line differ by at most this factor ...
STEP_TURN_DEG = 12.0    # ... and turn by at most this much at the grid's edge (bent_line_ends)
QUARTERS = ((-1, -1), (1, -1), (-1, 1), (1, 1))   # (sx, sy): the quarter at (c + 0.5 sx, c + 0.5 sy)


def _turn(ij: np.ndarray) -> np.ndarray:
    """A quarter turn of lattice labels (keeps handedness), as grid.orient turns them."""
    return np.stack([ij[..., 1], -ij[..., 0]], axis=-1)


def _holes(labels: set) -> list[tuple[tuple[int, int], list[tuple[int, int]]]]:
    """Missing lattice points (inside the grid's bounds) with at least MIN_RING of the 16 labels two
    steps around them found: (centre, ring labels found). The marker's rim corners, where a plain
    quarter meets two or three squares, are sometimes linked in, so the block need not be empty;
    its centre always is (the plain marker has no corner there)."""
    if not labels:
        return []
    arr = np.array(sorted(labels))
    lo, hi = arr.min(axis=0), arr.max(axis=0)
    out = []
    for ci in range(lo[0], hi[0] + 1):          # on the grid's last line too: a marker at the image's edge
        for cj in range(lo[1], hi[1] + 1):
            if (ci, cj) in labels:
                continue
            ring = [(ci + a, cj + b) for a in range(-2, 3) for b in range(-2, 3)
                    if max(abs(a), abs(b)) == 2 and (ci + a, cj + b) in labels]
            if len(ring) >= MIN_RING:
                out.append(((ci, cj), ring))
    return out


def _square_values(f: np.ndarray, Hm: np.ndarray, centres: np.ndarray, half: float = PATCH) -> np.ndarray:
    """Mean of ``f`` over a small patch around each lattice point ``centres`` (n, 2) (a square's
    centre), mapped into the image through the homography ``Hm``."""
    d = np.array([(a, b) for a in (-half, 0.0, half) for b in (-half, 0.0, half)], float)
    pts = (centres[:, None, :] + d[None]).reshape(-1, 1, 2)
    img = cv2.perspectiveTransform(pts, Hm).reshape(len(centres), len(d), 2)
    return sample(f, img[..., 0], img[..., 1]).mean(axis=1)


def _inside(shape, Hm: np.ndarray, pts: np.ndarray, margin: float = 1.0) -> np.ndarray:
    """Which lattice points ``pts`` (n, 2) map inside the image (``margin`` px from its edges)."""
    img = cv2.perspectiveTransform(np.asarray(pts, float)[:, None, :], Hm)[:, 0]
    return (img[:, 0] >= margin) & (img[:, 1] >= margin) & (img[:, 0] <= shape[1] - 1 - margin) & \
        (img[:, 1] <= shape[0] - 1 - margin)


def _read_marker(f: np.ndarray, pos: dict, centre, ring) -> tuple[tuple[int, int] | None, float]:
    """The dot's quarter (sx, sy) of the hole at ``centre`` if it is the marker, and how clearly
    (the dot's contrast over the plain quarters' spread); (None, 0) otherwise."""
    src = np.array(ring, float)
    dst = np.array([pos[t] for t in ring], float)
    Hm, _ = cv2.findHomography(src, dst, 0)
    if Hm is None:
        return None, 0.0
    c = np.array(centre, float)
    quarters = c + 0.5 * np.array(QUARTERS, float)
    # the 12 squares just outside the marker: the checker amplitude and mean
    outside = np.array([c + (a, b) for a in (-1.5, -0.5, 0.5, 1.5) for b in (-1.5, -0.5, 0.5, 1.5)
                        if max(abs(a), abs(b)) == 1.5], float)
    inside = _inside(f.shape, Hm, quarters)
    if not inside.all():
        return None, 0.0
    outside = outside[_inside(f.shape, Hm, outside)]       # a marker at the image's edge: what is seen
    parity = np.array([(int(round(a - 0.5)) + int(round(b - 0.5))) % 2 for a, b in outside - c], int)
    if min(int(np.sum(parity == 0)), int(np.sum(parity == 1))) < 2:
        return None, 0.0
    q = _square_values(f, Hm, quarters, DOT_PATCH)
    o = _square_values(f, Hm, outside)
    m0, m1 = o[parity == 0].mean(), o[parity == 1].mean()
    amp = abs(m1 - m0)
    if amp <= 0:
        return None, 0.0
    mid = (m0 + m1) / 2
    best, clarity = None, 0.0
    for k, (sx, sy) in enumerate(QUARTERS):
        plain = np.delete(q, k)
        spread = plain.max() - plain.min()
        dev = q[k] - plain.mean()
        if spread > QUIET * amp or abs(plain.mean() - mid) > MID_BAND * amp or abs(dev) < DOT_CONTRAST * amp:
            continue
        # the two squares sharing an edge with the dot's quarter have the other colour
        nb = np.array([c + (1.5 * sx, 0.5 * sy), c + (0.5 * sx, 1.5 * sy)])
        nb = nb[_inside(f.shape, Hm, nb)]
        if not len(nb) or np.any(np.sign(_square_values(f, Hm, nb) - plain.mean()) == np.sign(dev)):
            continue
        score = abs(dev) / max(spread, 1e-6 * amp)
        if score > clarity:
            best, clarity = (sx, sy), score
    return best, clarity


def bent_line_ends(xy: np.ndarray, ij: np.ndarray) -> np.ndarray:
    """Mask of corners that end a lattice line with a step unlike the line's next one: for labels
    a, b, c in a row (or column) with c at the grid's end of it, the step b -> c longer or shorter
    than a -> b by more than STEP_RATIO, or turned by more than STEP_TURN_DEG. A corner one square
    diagonally off at a steep, foreshortened rim links in as a row of its own whose every local
    check passes (a 36x28 board at 0.2 m through the Kannala-Brandt truth lens: 5 corners labelled
    (i + 1, j + 1), 8 px off); on a board the steps change smoothly. Repeated until none is left."""
    bad = np.zeros(len(xy), bool)
    pos = {tuple(t): k for k, t in enumerate(ij.tolist())}
    changed = True
    while changed:
        changed = False
        for t, k in list(pos.items()):
            for d in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                b = pos.get((t[0] - d[0], t[1] - d[1]))
                a = pos.get((t[0] - 2 * d[0], t[1] - 2 * d[1]))
                if a is None or b is None or (t[0] + d[0], t[1] + d[1]) in pos:
                    continue
                s1, s2 = xy[b] - xy[a], xy[k] - xy[b]
                n1, n2 = np.linalg.norm(s1), np.linalg.norm(s2)
                turn = np.degrees(np.arccos(np.clip(s1 @ s2 / max(n1 * n2, 1e-9), -1, 1)))
                if not (1 / STEP_RATIO <= n2 / max(n1, 1e-9) <= STEP_RATIO) or turn > STEP_TURN_DEG:
                    bad[k] = changed = True
                    del pos[t]
                    break
    return bad


def detect_marker_board(image: np.ndarray, board: tuple[int, int] = (10, 7)) -> Detection:
    """Find the W x H inner corners of a marker checkerboard (calibration/targets/spec.py) in a
    thermal image. Corners are in grid order with corner (0, 0) the board's own top-left corner
    (the marker's dot marks it, whatever the board's roll); the marker's 3 x 3 corners are never
    reported."""
    W, H = int(board[0]), int(board[1])
    mi, mj = marker_centre((W, H))          # TargetError for a board too small for the marker
    lat, why = find_lattice(image, (W, H))
    if why:
        return empty_detection((W, H), why, lat.n_candidates if lat is not None else 0)
    xy, ij = lat.xy, right_handed(lat.xy, lat.ij)
    pos = {tuple(t): (float(p[0]), float(p[1])) for t, p in zip(ij.tolist(), xy.tolist())}
    found = []
    for centre, ring in _holes(set(pos)):
        dot, clarity = _read_marker(lat.f, pos, centre, ring)
        if dot is not None:
            found.append((clarity, centre, dot))
    if not found:
        return empty_detection((W, H), "marker not found (the board's central marker is not in view, or it is "
                               "covered); a marker board is labelled only from its marker", lat.n_candidates)
    if len(found) > 1:
        return empty_detection((W, H), f"{len(found)} places look like the marker; cannot tell which",
                               lat.n_candidates)
    _, centre, dot = found[0]
    rel = ij - np.array(centre)
    d = np.array(dot)
    for _ in range(4):
        if tuple(d) == (-1, -1):
            break
        rel, d = _turn(rel), _turn(d)
    bij = rel + np.array([mi, mj])
    lo, hi = bij.min(axis=0), bij.max(axis=0)
    if lo[0] < 0 or lo[1] < 0 or hi[0] >= W or hi[1] >= H:
        span = hi - lo + 1
        return empty_detection((W, H), f"found corners over {span[0]}x{span[1]} lattice points around the "
                               f"marker: the board has at least {span[0]}x{span[1]} corners, not {W}x{H}; check "
                               f"--board (inner corners across x down)", lat.n_candidates)
    why = _wrong_size(lat.g, xy, bij, W, H)
    if why:
        return empty_detection((W, H), why, lat.n_candidates)
    block = marker_block((W, H))
    keep = ~block[bij[:, 1] * W + bij[:, 0]]
    keep[keep] = ~bent_line_ends(xy[keep], bij[keep])
    if int(keep.sum()) < MIN_CORNERS:
        return empty_detection((W, H), "too few corners around the marker", lat.n_candidates)
    return finish(lat, xy[keep], bij[keep], (W, H), absent=block)


def _wrong_size(g: np.ndarray, xy: np.ndarray, bij: np.ndarray, W: int, H: int) -> str:
    """Why the labels cannot be this W x H board: a board edge seen where the board has more corners
    (the board is smaller than --board). Empty if nothing says so."""
    lo, hi = bij.min(axis=0), bij.max(axis=0)
    for axis, n_board in ((0, W), (1, H)):
        ends = [board_edge_seen(g, xy, bij - lo, axis, end) for end in (0, 1)]
        if (ends[0] and lo[axis] > 0) or (ends[1] and hi[axis] < n_board - 1):
            name = "across" if axis == 0 else "down"
            n = hi[axis] - lo[axis] + 1
            has = f"it has {n} corners {name}" if all(ends) else f"it has fewer than {n_board} corners {name}"
            return (f"the board ends after {n} corners {name} where a {W}x{H} marker board goes on: {has}, "
                    f"not {n_board}; check --board")
    return ""

