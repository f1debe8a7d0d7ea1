"""detect_corners(image, board=(W, H)): the heated-checkerboard detector, end to end."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from .candidates import find_candidates, normalise
from .complete import complete
from .grid import anchor, label, link, orient
from .grow import grow, lattice_outliers
from .refine import image_noise, levels, refine

MIN_CORNERS = 6


@dataclass(frozen=True)
class Detection:
    """One image's board: ``corners`` (H*W, 2) in grid order (row j, then column i; top-left first),
    NaN where a corner was not found; ``level`` (H*W,) mrcal's level (0 best, -1 not found);
    ``weight`` = 2^-level (0 where not found)."""
    board: tuple[int, int]
    corners: np.ndarray
    level: np.ndarray
    reason: str = ""
    candidates: int = 0
    extra: dict = field(default_factory=dict)

    @property
    def found(self) -> int:
        return int(np.sum(np.isfinite(self.corners[:, 0])))

    @property
    def detected(self) -> bool:
        return self.found > 0

    @property
    def complete(self) -> bool:
        return self.found == self.board[0] * self.board[1]

    @property
    def weight(self) -> np.ndarray:
        return np.where(self.level >= 0, 2.0 ** (-self.level.astype(float)), 0.0)


def _empty(board, reason, n_cand=0) -> Detection:
    n = board[0] * board[1]
    return Detection(board, np.full((n, 2), np.nan), -np.ones(n, int), reason, n_cand)


def to_float(image: np.ndarray) -> np.ndarray:
    img = np.asarray(image)
    if img.ndim == 3:
        img = img[..., :3].mean(axis=2) if img.shape[2] >= 3 else img[..., 0]
    if img.ndim != 2:
        raise ValueError(f"expected a single-channel image, got shape {img.shape}")
    return img.astype(np.float32)


OCCLUDER_RANGE = 2.0    # x the board's median: a corner's neighbourhood spanning more is touched


def touched(f: np.ndarray, xy: np.ndarray, spacing: np.ndarray) -> np.ndarray:
    """Corners that something much hotter or colder than the board touches (a hand over the board,
    a warm object at its rim): the intensity range within max(3, 0.25 x spacing) px exceeds
    OCCLUDER_RANGE x the median range over the board's corners (a blurred X-corner spans the board's
    hot-to-cold contrast, a hand several times that). The hand's edge against the squares can make
    a saddle that passes every other check, a few px from the covered corner (seed 200 hard 7x7
    035: reported 4.9 px off)."""
    ok = np.isfinite(xy[:, 0])
    out = np.zeros(len(xy), bool)
    if ok.sum() < MIN_CORNERS:
        return out
    g = cv2.blur(f, (3, 3))
    H, W = f.shape
    rng = np.full(len(xy), np.nan)
    for k in np.flatnonzero(ok):
        r = int(math.ceil(max(3.0, 0.25 * spacing[k])))
        x, y = int(round(xy[k, 0])), int(round(xy[k, 1]))
        win = g[max(y - r, 0):min(y + r + 1, H), max(x - r, 0):min(x + r + 1, W)]
        rng[k] = float(win.max() - win.min())
    return ok & (rng > OCCLUDER_RANGE * np.nanmedian(rng))


def detect_corners(image: np.ndarray, board: tuple[int, int] = (10, 7)) -> Detection:
    """Find the W x H inner corners of a (heated) checkerboard in a thermal image (16-bit counts,
    8-bit, or float; one channel). Partial and occluded boards give the corners seen, at their board
    coordinates; corner (0, 0) is the top-left corner as seen in the image (see grid.py)."""
    W, H = int(board[0]), int(board[1])
    if W < 2 or H < 2:
        raise ValueError(f"board {W}x{H}: needs at least 2x2 inner corners")
    f = normalise(to_float(image))
    if float(f.max() - f.min()) <= 0:
        return _empty((W, H), "the image is flat (every pixel the same)")
    noise = image_noise(f)
    cands, g, S, local_sd = find_candidates(f, noise=noise)
    if len(cands.xy) < MIN_CORNERS:
        return _empty((W, H), "no checkerboard corners found", len(cands.xy))
    slots = link(cands)
    idx, ij = label(cands, slots)
    if len(idx) < MIN_CORNERS:
        return _empty((W, H), "no grid of corners found", len(cands.xy))
    # fill the holes and extend the runs the linking missed
    xy, ij, _ = grow(g, S, cands.xy[idx], ij, cands.strength[idx], (W, H))
    if len(xy) < MIN_CORNERS:
        return _empty((W, H), "no grid of corners found", len(cands.xy))
    ij, why = orient(xy, ij, W, H)
    if why:
        return _empty((W, H), why, len(cands.xy))
    keep = ij[:, 0] >= 0
    xy, ij = xy[keep], ij[keep]
    if len(xy) < MIN_CORNERS:
        return _empty((W, H), "no grid of corners found", len(cands.xy))
    ij = ij - ij.min(axis=0)
    if ij[:, 0].max() < 1 or ij[:, 1].max() < 1:
        return _empty((W, H), "only one row of corners found", len(cands.xy))
    ij, why = anchor(g, xy, ij, W, H)
    if ij is None:
        return _empty((W, H), why, len(cands.xy))
    # spacing to the nearest grid neighbour, for window sizes
    pos = {tuple(k): p for k, p in zip(ij.tolist(), xy.tolist())}
    spacing = np.array([min([math.sqrt((pos[n][0] - p[0]) ** 2 + (pos[n][1] - p[1]) ** 2) for n in
                             ((i + 1, j), (i - 1, j), (i, j + 1), (i, j - 1)) if n in pos] or [8.0])
                        for (i, j), p in zip(ij.tolist(), xy.tolist())])
    fine = refine(f, xy, spacing)
    fine[lattice_outliers(fine, ij)] = np.nan
    fine[touched(f, fine, spacing)] = np.nan
    ok = np.isfinite(fine[:, 0])
    # board corners still missing (too faint for the growth, dropped by the refinement): predicted
    # from the anchored grid, kept where the image shows that corner (complete.py)
    fine, ij, _ = complete(f, S, fine[ok], ij[ok], (W, H), noise)
    corners = np.full((W * H, 2), np.nan)
    lv = -np.ones(W * H, int)
    k = ij[:, 1] * W + ij[:, 0]
    corners[k] = fine
    lv[k] = levels(f, fine, local_sd, noise)
    return Detection((W, H), corners, lv, "", len(cands.xy))
