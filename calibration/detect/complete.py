"""Completing an anchored board: the corners the growth never added, predicted from the grid and
accepted only where the image shows that very corner.

After anchoring, every label (i, j) is a board coordinate, so a missing label inside the W x H
board is a real board corner whose place the labelled corners around it predict; its label cannot
be wrong, only its evidence. The growth (grow.py) has to judge lattice points before the grid is
placed on the board, where a point past the board's last corner line (its border and the
background on one side) looks like a faint board corner: its weakest-square limits therefore miss
a board corner whose outer square is faint or blurred, or a far column at the limit. Here:

* prediction: a local quadratic (i, j) -> (x, y) fitted to the labelled corners within 2 (else 3)
  lattice steps, weighted by 1 / distance^2 (on the bench's sets 0.05 px median error inside the
  grid, 0.2 px at a board corner or a whole missing column; the median of line extrapolations
  was 3-4 x worse), with the local steps u (+i) and v (+j) from its derivatives. Only labels next
  to the grid, round by round (a missing column or a hole fills from its rim);
* a saddle: the quadratic saddle fit (refine.saddle_fit) converges within max(1 px, 0.1 step) of
  the prediction, started there and at the strongest saddle response near it (two different
  saddles there: ambiguous, refused); on a board with steps of 16 px or more, where both fail, from
  the saddle of the image blurred in proportion to the step (a large, faint X-corner is beyond the
  fit's 1.5 px steps from a prediction 2-4 px off);
* the checker, on the destriped image itself (the local-contrast image the growth judges is
  distorted near the board's rim, where the background enters its window): 64 samples on the four
  quarter-squares (0.15-0.45 steps along u and v; shrunk towards the corner, down to 0.35 x, near
  the image's edge) fitted by offset + gradient along u and v + amplitude x the checker's sign
  pattern; the saddle response (at least 0.05 of the grid's) on the same image, blurred as the
  saddle fit sees it (_PointSaddle). The amplitude, signed by the grid's parity at (i, j) (a saddle the wrong way round is
  not this corner), at least 0.3 of the grid's median, 2.5 x the fit's residual and 3 x the pixel
  noise; each half (the two squares on one side of either line) at least half the amplitude (a hand
  or the background over one side leaves that half flat); the gradient at most half the amplitude
  (an edge, or a corner of the board's rim against the background, slopes);
* then refine() (as every corner) from the saddle found: its result within the same distance of
  the prediction and 0.5 px of the saddle (where refine drops a faint corner because cornerSubPix
  wandered more than 2 px, the saddle fit stands if it is the fit's fixed point), and the lattice
  check (grow.lattice_outliers) of the whole grid with the new corners; a new corner that puts an
  old one off the lattice goes.

Measured with these limits on the bench's sets (seeds 100, 200, 300, on which they were chosen;
real and hard, 10x7 and 7x7): of 12 424 lattice points one step past the board (the points most
like a faint board corner) and 102 corners under a hand, none passes; of 5 958 labelled corners
left out one at a time, 99.9 % pass. On seeds 400, 500, 600 (rendered as a check; their misses
led to the shrunk frame near the image's edge and the refine fall-back, not to other limits): 0 of
13 071 and 0 of 125 pass, 99.8 % of 6 214.
"""
from __future__ import annotations

import math

import cv2
import numpy as np

from .candidates import sample, saddle_response
from .grow import lattice_outliers
from .refine import SADDLE_BLUR, SADDLE_ITERS, refine, saddle_fit

MAX_ROUNDS = 8
MIN_CORNERS = 8              # labelled corners before anything is predicted
FIT_TOL = 0.1                # saddle within max(FIT_TOL_PX, FIT_TOL x step) of the prediction
FIT_TOL_PX = 1.0
SEARCH = 0.8                 # the saddle response's peak searched within this x the fit tolerance
REFINE_AGREE = 0.5           # px: refine's result and the saddle found, and two saddles, at most this apart
COARSE_STEP = 16.0           # px: boards this large get a coarse-scale start too
COARSE_BLUR = 0.08           # ... at a blur of this x the step
MIN_SADDLE = 0.05            # saddle response, share of the grid's median (a floor: the fit found the saddle)
MIN_AMP = 0.3                # checker amplitude, share of the grid's median
MIN_AMP_T = 2.5              # ... and over the residual of the checker fit
MIN_HALF = 0.5               # each half's amplitude, share of the whole amplitude
MAX_GRAD = 0.5               # gradient across the corner (half its change over a step) over the amplitude
MIN_CNR = 3.0                # amplitude over the pixel noise
RETRY_MOVE = 0.25            # px: a refused label is judged again once its prediction moved this much
MIN_SCALE = 0.35             # near the image's edge the samples may shrink towards the corner to this share
                             # (0.6 missed stereographic hard seed 11 024's corner (0, 0), 7 px from the top
                             # edge of a board foreshortened there: 0.38)

_OFF = np.array([0.15, 0.25, 0.35, 0.45])
_A, _B = [x.ravel() for x in np.meshgrid(np.concatenate([-_OFF[::-1], _OFF]),
                                          np.concatenate([-_OFF[::-1], _OFF]))]
_X = np.stack([np.ones_like(_A), _A, _B, np.sign(_A) * np.sign(_B)], 1)
_PINV = np.linalg.pinv(_X)                               # (4, 64)


def _half_weights() -> np.ndarray:
    """(64, 4): a sample vector times these gives the checker amplitude measured on each half
    (v > 0, v < 0 across the u line; u > 0, u < 0 across the v line): half the difference of the
    two squares' means, signed like the whole pattern."""
    out = np.zeros((len(_A), 4))
    chk = np.sign(_A) * np.sign(_B)
    for k, half in enumerate((_B > 0, _B < 0, _A > 0, _A < 0)):
        pos, neg = half & (chk > 0), half & (chk < 0)
        out[pos, k] = 0.5 / pos.sum()
        out[neg, k] = -0.5 / neg.sum()
    return out


_HALF = _half_weights()


def checker_fit(img: np.ndarray, p: np.ndarray, u: np.ndarray, v: np.ndarray):
    """Checker fit on 64 samples of ``img`` around each point ``p`` (n, 2) in its lattice frame
    (u, v: (n, 2) steps along +i and +j): (amplitude (n,), residual sd (n,), the largest gradient
    term (n,), the four half amplitudes (n, 4)); the amplitude is positive where the square at
    +u+v is the brighter one."""
    px = p[:, 0:1] + _A[None] * u[:, 0:1] + _B[None] * v[:, 0:1]
    py = p[:, 1:2] + _A[None] * u[:, 1:2] + _B[None] * v[:, 1:2]
    y = sample(img, px, py).astype(float)
    coef = y @ _PINV.T
    res = y - coef @ _X.T
    rsd = np.sqrt(np.sum(res * res, axis=1) / (len(_A) - 4))
    grad = 0.5 * np.maximum(np.abs(coef[:, 1]), np.abs(coef[:, 2]))
    return coef[:, 3], rsd, grad, y @ _HALF


def predict(pos: dict, t: tuple[int, int]):
    """(position, u, v) of lattice point ``t`` from a local quadratic fitted to the labelled
    points ``pos`` ((i, j) -> (x, y)) within 2 lattice steps (3 if that is too few); None when
    they cannot fix one."""
    for rad in (2, 3):
        r = _poly(pos, t, rad)
        if r is not None:
            return r
    return None


def _poly(pos: dict, t: tuple[int, int], rad: int):
    s, d = [], []
    for (a, b), p in pos.items():
        da, db = a - t[0], b - t[1]
        if (da or db) and -rad <= da <= rad and -rad <= db <= rad:
            s.append((da, db))
            d.append(p)
    if len(s) < 6:
        return None
    s = np.array(s, float)
    a, b = s[:, 0], s[:, 1]
    na, nb = len(np.unique(a)), len(np.unique(b))
    if na < 2 or nb < 2:
        return None
    cols = [np.ones_like(a), a, b, a * b]
    if na >= 3:
        cols.append(a * a)
    if nb >= 3:
        cols.append(b * b)
    X = np.stack(cols, 1)
    if len(s) < X.shape[1] + 2:
        return None
    w = 1.0 / np.sqrt(a * a + b * b)
    c, _, rank, _ = np.linalg.lstsq(X * w[:, None], np.array(d, float) * w[:, None], rcond=None)
    if rank < X.shape[1]:
        return None
    return c[0], c[1], c[2]


def _scale_inside(p, u, v, Ww: int, Hh: int) -> float:
    """The largest share (at most 1) of the sampling frame around ``p`` (0.45 steps along u and v)
    that stays inside the image, with the saddle fit's 3-pixel window."""
    reach = 0.45 * (np.abs(u) + np.abs(v))
    room = np.minimum(np.asarray(p) - 3.0, np.array([Ww - 4.0, Hh - 4.0]) - p)
    if np.any(room <= 0):
        return 0.0
    return float(min(1.0, np.min(room / np.maximum(reach, 1e-9))))


def _grid_reference(f: np.ndarray, S: np.ndarray, pos: dict):
    """The grid's checker parity (+1 where the square at +u+v of an even (i + j) corner is the
    brighter), median checker amplitude and median saddle response, from its labelled corners
    (steps from their neighbours)."""
    keys = np.array(list(pos), int)
    k0 = keys.min(0)
    ni, nj = keys.max(0) - k0 + 1
    G = np.full((nj + 2, ni + 2, 2), np.nan)           # one empty line all round
    G[keys[:, 1] - k0[1] + 1, keys[:, 0] - k0[0] + 1] = [pos[tuple(t)] for t in keys.tolist()]

    def mean2(a, b):                                  # mean of the finite ones, NaN if neither
        fa, fb = np.isfinite(a), np.isfinite(b)
        with np.errstate(invalid="ignore"):
            return (np.where(fa, a, 0.0) + np.where(fb, b, 0.0)) / (fa.astype(float) + fb)
    U = mean2(G[1:-1, 2:] - G[1:-1, 1:-1], G[1:-1, 1:-1] - G[1:-1, :-2])
    V = mean2(G[2:, 1:-1] - G[1:-1, 1:-1], G[1:-1, 1:-1] - G[:-2, 1:-1])
    jj, ii = keys[:, 1] - k0[1], keys[:, 0] - k0[0]
    P, U, V = G[jj + 1, ii + 1], U[jj, ii], V[jj, ii]
    ok = np.isfinite(U[:, 0]) & np.isfinite(V[:, 0])
    if ok.sum() < 4:
        return None
    sgn = np.where(keys[ok].sum(1) % 2 == 0, 1.0, -1.0)
    amp = checker_fit(f, P[ok], U[ok], V[ok])[0] * sgn
    parity = 1.0 if np.sum(np.sign(amp)) >= 0 else -1.0
    Pk = np.rint(P[ok]).astype(int)
    return parity, float(np.median(np.abs(amp))), float(np.median(S[Pk[:, 1], Pk[:, 0]]))


def _coarse_start(f: np.ndarray, p: np.ndarray, step: float, radius: float) -> np.ndarray:
    """A start for the saddle fit near ``p`` on a large board: the strongest saddle response of the
    image blurred in proportion to the step (COARSE_BLUR x step) within ``radius`` of ``p``, fitted
    at that blur. (The fit's steps are limited to 1.5 px, and the saddle response at the candidates'
    scale is noisy across a large, faint X-corner: a prediction 2-4 px off never reached it.)"""
    sc = float(np.clip(COARSE_BLUR * step, 1.5, 5.0))
    Hh, Ww = f.shape
    R = int(math.ceil(radius + 3 * sc + 3))
    cx, cy = int(round(p[0])), int(round(p[1]))
    x0, y0 = max(cx - R, 0), max(cy - R, 0)
    patch = f[y0:min(cy + R + 1, Hh), x0:min(cx + R + 1, Ww)]
    if min(patch.shape) < 8:
        return np.full(2, np.nan)
    Sc = saddle_response(cv2.GaussianBlur(patch, (0, 0), sc))
    yy, xx = np.mgrid[0:patch.shape[0], 0:patch.shape[1]]
    Sc = np.where((xx + x0 - p[0]) ** 2 + (yy + y0 - p[1]) ** 2 <= radius * radius, Sc, -np.inf)
    ky, kx = np.unravel_index(int(np.argmax(Sc)), Sc.shape)
    if not Sc[ky, kx] > 0:
        return np.full(2, np.nan)
    fit = saddle_fit(patch, np.array([[kx, ky]], float), blur=sc, r=max(3, int(round(1.5 * sc))), iters=5)
    return fit[0] + [x0, y0]


def _saddle_near(f, blurred, S, p, tol, step) -> np.ndarray:
    """The saddle-fit corner near each prediction ``p`` (n, 2), NaN where none lies within ``tol``
    (n,) of it. The fit starts at the prediction and at the strongest saddle response within
    SEARCH x tol of it (on a large board the prediction can be a few pixels off, beyond the fit's
    reach); where both converge, apart, the place is ambiguous (NaN). Where neither does, on a
    board with steps of COARSE_STEP or more, from a coarse-scale saddle (_coarse_start)."""
    Hh, Ww = S.shape
    R = int(math.ceil(float(np.max(SEARCH * tol))))
    oy, ox = np.mgrid[-R:R + 1, -R:R + 1]
    oy, ox = oy.ravel(), ox.ravel()
    c = np.rint(p).astype(int)
    X = np.clip(c[:, 0:1] + ox[None], 0, Ww - 1)
    Y = np.clip(c[:, 1:2] + oy[None], 0, Hh - 1)
    d2 = (X - p[:, 0:1]) ** 2 + (Y - p[:, 1:2]) ** 2
    k = np.argmax(np.where(d2 <= (SEARCH * tol[:, None]) ** 2, S[Y, X], -np.inf), axis=1)
    rows = np.arange(len(p))
    peak = np.stack([X[rows, k], Y[rows, k]], 1).astype(float)
    fits = saddle_fit(f, np.vstack([p, peak]), iters=5, blurred=blurred).reshape(2, len(p), 2)
    with np.errstate(invalid="ignore"):
        near = np.linalg.norm(fits - p[None], axis=2) <= tol[None]
        apart = np.linalg.norm(fits[0] - fits[1], axis=1) > REFINE_AGREE
    out = np.where(near[0][:, None], fits[0], np.where(near[1][:, None], fits[1], np.nan))
    out[near[0] & near[1] & apart] = np.nan
    for n in np.flatnonzero(~near[0] & ~near[1] & (step >= COARSE_STEP)):
        c0 = _coarse_start(f, p[n], step[n], SEARCH * tol[n])
        if np.isfinite(c0[0]):
            fit = saddle_fit(f, c0[None], iters=5, blurred=blurred)[0]
            with np.errstate(invalid="ignore"):
                if np.linalg.norm(fit - p[n]) <= tol[n]:
                    out[n] = fit
    return out


class _PointSaddle:
    """candidates.saddle_response of ``g`` (Sobel 3x3 second derivatives: Ixy^2 - Ixx Iyy), indexed
    like an array (``S[y, x]``, integer pixel arrays) but evaluated only
    there: the whole image's costs 5-9 ms, the few hundred pixels the completion looks at ~0.1 ms."""

    def __init__(self, g: np.ndarray):
        self.g = g
        self.shape = g.shape

    def __getitem__(self, yx):
        g = self.g
        y = np.clip(np.asarray(yx[0], int), 1, g.shape[0] - 2)     # the image's edge pixels: their
        x = np.clip(np.asarray(yx[1], int), 1, g.shape[1] - 2)     # inner neighbour's response

        def at(dy, dx):
            return g[y + dy, x + dx].astype(np.float64)
        c = at(0, 0)
        ixx = (at(-1, -1) - 2 * at(-1, 0) + at(-1, 1)) + 2 * (at(0, -1) - 2 * c + at(0, 1)) \
            + (at(1, -1) - 2 * at(1, 0) + at(1, 1))
        iyy = (at(-1, -1) - 2 * at(0, -1) + at(1, -1)) + 2 * (at(-1, 0) - 2 * c + at(1, 0)) \
            + (at(-1, 1) - 2 * at(0, 1) + at(1, 1))
        ixy = at(-1, -1) - at(-1, 1) - at(1, -1) + at(1, 1)
        return ixy * ixy - ixx * iyy


def _evidence(f, S, p, u, v, t, parity, med_amp, med_S, noise) -> np.ndarray:
    """Which of the points ``p`` (n, 2) with lattice frames u, v and labels ``t`` look like this
    grid's corner (i, j) on the image ``f``: saddle response, checker amplitude and parity, both
    halves, gradient, contrast over noise (the limits at the top of this module)."""
    Hh, Ww = S.shape
    c = np.clip(np.rint(p).astype(int), 1, [Ww - 2, Hh - 2])
    s_peak = np.max([S[c[:, 1] + dy, c[:, 0] + dx] for dy in (-1, 0, 1) for dx in (-1, 0, 1)], axis=0)
    sgn = parity * np.where(t.sum(1) % 2 == 0, 1.0, -1.0)
    amp, rsd, grad, half = checker_fit(f, p, u, v)
    amp, half = amp * sgn, half * sgn[:, None]
    return ((s_peak >= MIN_SADDLE * med_S) & (amp >= MIN_AMP * med_amp) & (amp >= MIN_AMP_T * rsd)
            & (half.min(1) >= MIN_HALF * amp) & (grad <= MAX_GRAD * amp) & (amp >= MIN_CNR * noise))


def complete(f: np.ndarray, S: np.ndarray, xy: np.ndarray, ij: np.ndarray, board: tuple[int, int],
             noise: float):
    """Add the board corners missing from the anchored grid (xy refined, ij board coordinates, no
    NaN) where the image shows them: returns (xy, ij, added mask). ``f`` is the destriped image
    (refine's input), ``S`` the saddle response of the candidates, ``noise`` the pixel noise of
    ``f``."""
    W, H = board
    n0 = len(xy)
    none = np.zeros(n0, bool)
    if n0 < MIN_CORNERS or n0 >= W * H:
        return xy, ij, none
    pos = {(int(i), int(j)): (float(x), float(y)) for (i, j), (x, y) in zip(ij.tolist(), xy.tolist())}
    # the saddle response judged, like the checker, on the destriped image (blurred as the saddle
    # fit sees it): the candidates' S is computed on the local-contrast image, which a hot object
    # behind the board's rim squashes (its 21 px window takes the object's contrast in). Stereographic
    # hard seed 11 image 001: the last row's three corners at 0.03-0.04 of the grid's S there, with
    # amplitudes of 0.74-0.81 of the grid's and clean halves; on the destriped image they pass.
    blurred = cv2.GaussianBlur(f, (0, 0), SADDLE_BLUR)
    S_f = _PointSaddle(blurred)
    ref = _grid_reference(f, S_f, pos)
    if ref is None:
        return xy, ij, none
    parity, med_amp, med_S = ref
    if med_amp <= 0 or med_S <= 0:
        return xy, ij, none
    Hh, Ww = f.shape
    seen: dict = {}                 # label -> the prediction it was last judged at
    new: dict = {}
    for _ in range(MAX_ROUNDS):
        T, PR, US, VS, STEP = [], [], [], [], []
        for j in range(H):
            for i in range(W):
                t = (i, j)
                if t in pos or not any((i + a, j + b) in pos for a in (-1, 0, 1) for b in (-1, 0, 1)):
                    continue
                r = predict(pos, t)
                if r is None:
                    continue
                p, u, v = r
                if t in seen and math.dist(seen[t], p) < RETRY_MOVE:
                    continue                # judged before at (nearly) this place
                seen[t] = (float(p[0]), float(p[1]))
                k = _scale_inside(p, u, v, Ww, Hh)
                if k < MIN_SCALE:
                    continue
                STEP.append(min(math.hypot(*u), math.hypot(*v)))
                # the checker is sampled in a frame shrunk by k (a corner close to the image's edge)
                T.append(t), PR.append(p), US.append(u * k), VS.append(v * k)
        if not T:
            break
        T, PR, US, VS, step = np.array(T), np.array(PR), np.array(US), np.array(VS), np.array(STEP)
        tol = np.maximum(FIT_TOL_PX, FIT_TOL * step)
        sad = _saddle_near(f, blurred, S, PR, tol, step)
        ok = np.isfinite(sad[:, 0])
        if not ok.any():
            continue
        T, PR, US, VS, sad, step, tol = T[ok], PR[ok], US[ok], VS[ok], sad[ok], step[ok], tol[ok]
        ok = _evidence(f, S_f, sad, US, VS, T, parity, med_amp, med_S, noise)
        if not ok.any():
            continue
        for t, p, q, st, tl in zip(map(tuple, T[ok].tolist()), sad[ok].tolist(), PR[ok].tolist(), step[ok], tol[ok]):
            pos[t] = (p[0], p[1])
            new[t] = (q, st, tl)
    if not new:
        return xy, ij, none
    # the position every other corner gets (refine), from the saddle found; it must stay there.
    # Where refine drops it (cornerSubPix more than 2 px from the saddle fit, on a faint corner)
    # the saddle fit stands if it is a fixed point of the fit
    keys = list(new)
    sad = np.array([pos[t] for t in keys])
    pred = np.array([new[t][0] for t in keys])
    step = np.array([new[t][1] for t in keys])
    tol = np.array([new[t][2] for t in keys])
    fine = refine(f, sad, step)
    lost = ~np.isfinite(fine[:, 0])
    if lost.any():
        again = saddle_fit(f, sad[lost], iters=SADDLE_ITERS, blurred=blurred)
        with np.errstate(invalid="ignore"):
            stable = np.linalg.norm(again - sad[lost], axis=1) <= 0.05
        fine[np.flatnonzero(lost)[stable]] = sad[lost][stable]
    with np.errstate(invalid="ignore"):
        ok = (np.linalg.norm(fine - pred, axis=1) <= tol) & (np.linalg.norm(fine - sad, axis=1) <= REFINE_AGREE)
    for t, p, good in zip(keys, fine.tolist(), ok):
        if good:
            pos[t] = (p[0], p[1])
        else:
            del pos[t], new[t]
    if not new:
        return xy, ij, none
    # the lattice check with the new corners: a new corner off the lattice goes, and so does a new
    # one next to an old corner that the new corners put off the lattice (the old ones stay)
    keys = list(pos)
    P = np.array([pos[t] for t in keys], float)
    K = np.array(keys, int)
    is_new = np.array([t in new for t in keys])
    for _ in range(len(new) + 1):
        bad = lattice_outliers(P, K)
        drop = bad & is_new
        for t in K[bad & ~is_new].tolist():
            near = is_new & (np.abs(K[:, 0] - t[0]) <= 1) & (np.abs(K[:, 1] - t[1]) <= 1)
            drop |= near
        if not drop.any():
            break
        keep = ~drop
        P, K, is_new = P[keep], K[keep], is_new[keep]
    return P, K, is_new


def corners_past(f: np.ndarray, S: np.ndarray, xy: np.ndarray, ij: np.ndarray, axis: int, line: int,
                 noise: float) -> tuple[int, int]:
    """How many lattice points of the line ``line`` along ``axis`` (a line just past the grid:
    -1, or one past its largest label) look like this grid's corners on the destriped image ``f``,
    judged as the completion judges a missing corner (the saddle near the prediction, then the
    checker evidence); returns (passed, judged). A line the anchoring says lies past the board's
    edge must hold none: a hand over the squares past the last line found looks as plain as the
    border, and a board larger than --board whose extra corners were all missed ends where the
    board does not."""
    pos = {(int(i), int(j)): (float(x), float(y)) for (i, j), (x, y) in zip(ij.tolist(), xy.tolist())}
    if len(pos) < MIN_CORNERS:
        return 0, 0
    blurred = cv2.GaussianBlur(f, (0, 0), SADDLE_BLUR)
    S_f = _PointSaddle(blurred)
    ref = _grid_reference(f, S_f, pos)
    if ref is None:
        return 0, 0
    parity, med_amp, med_S = ref
    if med_amp <= 0 or med_S <= 0:
        return 0, 0
    Hh, Ww = f.shape
    inward = 1 if line < 0 else -1
    T, PR, US, VS, STEP = [], [], [], [], []
    for t0 in pos:
        if t0[axis] != line + inward:
            continue
        t = list(t0)
        t[axis] = line
        t = tuple(t)
        r = predict(pos, t)
        if r is None:
            continue
        p, u, v = r
        k = _scale_inside(p, u, v, Ww, Hh)
        if k < MIN_SCALE:
            continue
        T.append(t), PR.append(p), US.append(u * k), VS.append(v * k)
        STEP.append(min(math.hypot(*u), math.hypot(*v)))
    if not T:
        return 0, 0
    T, PR, US, VS, step = np.array(T), np.array(PR), np.array(US), np.array(VS), np.array(STEP)
    tol = np.maximum(FIT_TOL_PX, FIT_TOL * step)
    sad = _saddle_near(f, blurred, S, PR, tol, step)
    ok = np.isfinite(sad[:, 0])
    if not ok.any():
        return 0, len(T)
    ev = _evidence(f, S_f, sad[ok], US[ok], VS[ok], T[ok], parity, med_amp, med_S, noise)
    return int(ev.sum()), len(T)
