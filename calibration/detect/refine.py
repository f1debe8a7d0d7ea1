"""Sub-pixel corner positions and how much to trust each.

Positions: OpenCV's cornerSubPix (every gradient in a window around an X-corner is orthogonal to
the vector from the corner: unbiased for straight edges at any angle, so for tilted boards too) on
a lightly smoothed copy of the destriped image, with a window sized from the local corner spacing.

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
    moved = np.linalg.norm(out - xy, axis=1)
    bad = (moved > np.maximum(2.0, 0.3 * spacing)) | (out[:, 0] < 0) | (out[:, 1] < 0) | \
        (out[:, 0] > W - 1) | (out[:, 1] > H - 1)
    out[bad] = np.nan
    return out.astype(np.float64)


def levels(f: np.ndarray, xy: np.ndarray, local_sd: np.ndarray, noise: float | None = None) -> np.ndarray:
    """mrcal level of each corner from its local contrast over the image noise. ``local_sd`` is the
    local standard deviation map (about half the square-to-square contrast on a board)."""
    if noise is None:
        noise = image_noise(f)
    xi = np.clip(np.rint(xy[:, 0]).astype(int), 0, f.shape[1] - 1)
    yi = np.clip(np.rint(xy[:, 1]).astype(int), 0, f.shape[0] - 1)
    cnr = 2.0 * local_sd[yi, xi] / noise
    return np.clip(np.ceil(np.log2(CNR_FULL / np.maximum(cnr, 1e-3))), 0, MAX_LEVEL).astype(int)
