"""Sub-pixel corner positions and how much to trust each.

Positions: OpenCV's cornerSubPix (every gradient in a window around an X-corner is orthogonal to
the vector from the corner: unbiased for straight edges at any angle, so for tilted boards too) on
a lightly smoothed copy of the destriped image, with a window sized from the local corner spacing;
then the saddle point of a local quadratic fit (``saddle_fit``, see below), from both the
cornerSubPix and the unrefined (grid) position: where cornerSubPix was pulled off (no saddle at
its result, or the two fits more than 0.3 px apart) the fit from the grid position is kept.

Trust: a corner's position noise grows with image noise over local contrast. ``level`` follows
mrcal's corners file: 0 for full trust, n for 2^n times the noise; ``weight`` = 2^-level.
"""
from __future__ import annotations

import cv2
import numpy as np

# measured on the "hard" set from truth + 0.4 px noise starts (rms / corners > 1 px off):
# blur 0.8, half-window 0.4 x spacing (<= 7): 0.30 px / 30; blur 0.6, 0.5 x spacing (<= 10): 0.22 / 1
REFINE_BLUR = 0.6
REFINE_WINDOW = 0.5
REFINE_MAX_HALF = 10
# then the saddle point of a quadratic fitted to a Gaussian-weighted 7x7 window of the image blurred
# by 1.5 px. An X-corner is point-symmetric (opposite squares alike), so the blurred image has zero
# gradient exactly at the corner whatever the blur and the angle between its lines, and the odd
# (cubic) terms vanish in a window centred on it: the fit is unbiased, and far less noisy than
# cornerSubPix at low contrast. Measured on the bench sets from truth + 0.4 px noise starts
# (rms of corners within 1 px / corners > 0.5 px off): hard 10x7 0.242 / 102 -> 0.150 / 18,
# hard 7x7 0.268 / 86 -> 0.187 / 28, real 10x7 0.036 -> 0.025.
SADDLE_BLUR = 1.5
SADDLE_R = 3
SADDLE_ITERS = 3
SADDLE_AGREE = 0.3     # px: fits further apart mean cornerSubPix was pulled off: the grid-position fit is kept
SADDLE_DISAGREE = 2.0   # px between cornerSubPix's and the fit's estimates: an unreliable corner, dropped
STUCK_PX = 1e-3        # refinement that moved a corner less than this did not measure it
CNR_FULL = 40.0       # contrast / noise at which a corner counts as level 0
MAX_LEVEL = 4


def image_noise(f: np.ndarray) -> float:
    """Robust std of the per-pixel temporal noise (MAD of a second difference along rows)."""
    f = f[::4]                                   # every 4th row: plenty of samples, 4x faster
    d = f[:, 2:] - 2 * f[:, 1:-1] + f[:, :-2]
    return float(1.4826 * np.median(np.abs(d - np.median(d)))) / np.sqrt(6.0) + 1e-6


def refine(f: np.ndarray, xy: np.ndarray, spacing: np.ndarray) -> np.ndarray:
    """Refined positions of the corners ``xy`` (n, 2); ``spacing`` is each corner's distance to its
    nearest grid neighbour (pixels)."""
    g = cv2.GaussianBlur(f, (0, 0), REFINE_BLUR)
    out = xy.astype(np.float32).copy()
    half = np.clip(np.floor(spacing * REFINE_WINDOW), 2, REFINE_MAX_HALF).astype(int)
    crit = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 40, 0.001)
    H, W = f.shape
    for h in np.unique(half):
        sel = np.flatnonzero(half == h)
        pts = out[sel].reshape(-1, 1, 2).copy()
        pts = cv2.cornerSubPix(g, pts, (int(h), int(h)), (-1, -1), crit)
        out[sel] = pts.reshape(-1, 2)
    out = out.astype(np.float64)
    gs = cv2.GaussianBlur(f, (0, 0), SADDLE_BLUR)         # one blur for both fits
    sad = saddle_fit(f, out, blurred=gs)
    # the fit from the unrefined position too: cornerSubPix can wander to the next saddle on a
    # steep, faint board; two fits that end apart mean the corner is not well defined (dropped)
    sad0 = saddle_fit(f, np.asarray(xy, float), iters=SADDLE_ITERS + 2, blurred=gs)
    with np.errstate(invalid="ignore"):
        apart = np.linalg.norm(sad - sad0, axis=1) > SADDLE_AGREE
    # cornerSubPix pulled off (its window holds the neighbouring corners of a small or steep
    # board: it lands where the fit finds no saddle, or at another one): the fit from the grid's
    # own position stands, and cornerSubPix's estimate is not held against it (lattice check follows)
    from0 = np.isfinite(sad0[:, 0]) & (~np.isfinite(sad[:, 0]) | apart)
    sad[from0] = sad0[from0]
    out[from0] = sad0[from0]
    with np.errstate(invalid="ignore"):
        disagree = np.linalg.norm(sad - out, axis=1) > SADDLE_DISAGREE
    # neither fit converges (from cornerSubPix's point nor from the grid's): nothing confirms
    # cornerSubPix's estimate, and on a large, faint corner it is the worst of all (stereographic hard,
    # marker board seed 60 view 4, corner (8, 5): 34 px squares, level 3, reported 1.03 px off; 4 such
    # corners of 3 953 on its set and the stereographic hard bench sets, 0.5-1.7 px off against 0.11-0.16
    # px RMS; on the real sets 0.17-0.60 px against 0.027): dropped. The completion
    # (complete.py) judges it again from the grid and keeps it where a saddle fit holds there
    unconfirmed = ~np.isfinite(sad[:, 0])
    out = np.where((disagree | unconfirmed)[:, None], np.nan, np.where(np.isfinite(sad), sad, out))
    moved = np.linalg.norm(out - xy, axis=1)
    # a corner that neither the saddle fit nor cornerSubPix moved was never measured: it sits where
    # the grid predicted it (5 of the 11 such corners on the detection bench's sets were 10-15 px
    # off, on a large faint board's rim, and kept their label)
    bad = (moved > np.maximum(2.0, 0.3 * spacing)) | (moved < STUCK_PX) | (out[:, 0] < 0) | (out[:, 1] < 0) | \
        (out[:, 0] > W - 1) | (out[:, 1] > H - 1)
    out[bad | ~np.isfinite(moved)] = np.nan
    return out


def _saddle_operator(r: int):
    oy, ox = np.mgrid[-r:r + 1, -r:r + 1]
    ox, oy = ox.ravel(), oy.ravel()
    A = np.stack([ox * ox, ox * oy, oy * oy, ox, oy, np.ones_like(ox)], 1).astype(float)
    w = np.exp(-(ox ** 2 + oy ** 2) / (2 * (r / 1.5) ** 2))
    return ox, oy, w, np.linalg.pinv(A * w[:, None])


def saddle_fit(f: np.ndarray, xy: np.ndarray, blur: float = SADDLE_BLUR, r: int = SADDLE_R,
               iters: int = SADDLE_ITERS, blurred: np.ndarray | None = None) -> np.ndarray:
    """Saddle point of a weighted quadratic fit around each point of ``xy`` on ``f`` blurred by
    ``blur`` (or on ``blurred``, that image already blurred); NaN where the fit is not a saddle,
    runs off the image or moves more than 1.5 px a step."""
    g = cv2.GaussianBlur(f, (0, 0), blur) if blurred is None else blurred
    ox, oy, w, P = _saddle_operator(r)
    out = np.array(xy, float)
    H, W = f.shape
    for _ in range(iters):
        fin = np.isfinite(out[:, 0])
        c = np.rint(np.where(fin[:, None], out, 0)).astype(int)
        ok = fin & (c[:, 0] >= r) & (c[:, 1] >= r) & (c[:, 0] <= W - 1 - r) & (c[:, 1] <= H - 1 - r)
        c = np.clip(c, r, [W - 1 - r, H - 1 - r])
        V = g[c[:, 1:2] + oy[None], c[:, 0:1] + ox[None]] * w[None]
        a, b, cc, d, e, _ = P @ V.T.astype(float)
        det = 4 * a * cc - b * b
        with np.errstate(divide="ignore", invalid="ignore"):
            step = np.stack([(-2 * cc * d + b * e) / det, (b * d - 2 * a * e) / det], 1)
        good = ok & (det < 0) & (np.abs(step).max(1) < 1.5)
        out = np.where(good[:, None], c + step, np.nan)
    return out


def levels(f: np.ndarray, xy: np.ndarray, local_sd: np.ndarray, noise: float | None = None) -> np.ndarray:
    """mrcal level of each corner from its local contrast over the image noise. ``local_sd`` is the
    local standard deviation map (about half the square-to-square contrast on a board)."""
    if noise is None:
        noise = image_noise(f)
    xi = np.clip(np.rint(xy[:, 0]).astype(int), 0, f.shape[1] - 1)
    yi = np.clip(np.rint(xy[:, 1]).astype(int), 0, f.shape[0] - 1)
    cnr = 2.0 * local_sd[yi, xi] / noise
    return np.clip(np.ceil(np.log2(CNR_FULL / np.maximum(cnr, 1e-3))), 0, MAX_LEVEL).astype(int)
