"""Which frames of a recording to calibrate from: sharp, not during a flat-field correction, and
together covering the image with diverse board poses.

- ``sharpness``: the variance of the Laplacian of the frame scaled by its own robust contrast (the
  0.5-99.5 percentile span), so a hotter board is not "sharper"; ``board_sharpness`` inside the
  convex hull of the board's detected corners, the smallest of four directional second-derivative
  variances (what the command uses: the whole frame's figure also grows with how much of it the
  board fills, and a smear along one direction hides in the Laplacian); ``sharp_mask`` keeps frames at least SHARP_SHARE
  of the recording's own median (the recording is its own reference: a Boson's counts, its lens and
  the board's heat spread set the scale, not a fixed number).
- ``frozen_mask``: a frame whose pixels repeat the previous frame's exactly (a Boson holds its last
  frame while the shutter is closed for an FFC); ``ffc_mask``: frames whose stamps fall inside an FFC
  span from the status topic, widened by FFC_MARGIN_NS on both sides (the frames right after an FFC
  still settle).
- ``coverage_greedy``: from the frames with a board, the next pick is the one adding the most
  coverage: the corners it adds to cells of a COVERAGE_GRID over the image that hold fewer than
  CELL_FULL chosen corners (up to CELL_FULL each, in units of CELL_FULL), plus POSE_WEIGHT x the distance of its
  pose (the board's apparent size and the aspect of its corners' spread, a tilt proxy) to the closest
  pose already chosen, until ``max_frames`` or no pick adds MIN_GAIN.
"""
from __future__ import annotations

import cv2
import numpy as np

SHARP_SHARE = 0.6            # of the recording's median sharpness
FFC_MARGIN_NS = 100_000_000  # 0.1 s around an FFC span
COVERAGE_GRID = (8, 6)       # cells across x down
CELL_FULL = 20              # corners in a cell that make it covered
POSE_WEIGHT = 0.25           # of a fresh cell, for a pose unlike those chosen
MIN_GAIN = 0.05              # stop when the best pick adds less than this


def sharpness(image: np.ndarray) -> float:
    """Variance of the Laplacian of ``image`` scaled to its 0.5-99.5 percentile span."""
    f = np.asarray(image, np.float32)
    lo, hi = np.percentile(f, [0.5, 99.5])
    if hi <= lo:
        return 0.0
    return float(cv2.Laplacian((f - lo) / (hi - lo), cv2.CV_32F, ksize=3).var())


_DIRECTIONAL = [np.array(k, np.float32) for k in (
    [[0, 0, 0], [1, -2, 1], [0, 0, 0]], [[0, 1, 0], [0, -2, 0], [0, 1, 0]],
    [[1, 0, 0], [0, -2, 0], [0, 0, 1]], [[0, 0, 1], [0, -2, 0], [1, 0, 0]])]


def board_sharpness(image: np.ndarray, corners: np.ndarray) -> float:
    """How sharp a board is: inside the convex hull of its detected corners (NaN rows ignored), the
    image scaled by the contrast there, the variance of its second derivative along each of four
    directions (0, 45, 90, 135 deg), the smallest of them (a smear along one direction, the hand
    moving, leaves the others sharp; the Laplacian sums them and hides it). Whatever else is in the
    frame and however much of it the board fills (a small, distant board is not "blurred")."""
    xy = np.asarray(corners, float)
    xy = xy[np.isfinite(xy[:, 0])]
    if len(xy) < 3:
        return 0.0
    f = np.asarray(image, np.float32)
    mask = np.zeros(f.shape, np.uint8)
    cv2.fillConvexPoly(mask, cv2.convexHull(np.rint(xy).astype(np.int32)), 1)
    inside = mask.astype(bool)
    if inside.sum() < 16:
        return 0.0
    lo, hi = np.percentile(f[inside], [0.5, 99.5])
    if hi <= lo:
        return 0.0
    g = (f - lo) / (hi - lo)
    core = cv2.erode(mask, np.ones((3, 3), np.uint8)).astype(bool)
    return min(float(cv2.filter2D(g, cv2.CV_32F, k)[core].var()) for k in _DIRECTIONAL)


def sharp_mask(values: np.ndarray, share: float = SHARP_SHARE) -> np.ndarray:
    """Frames at least ``share`` of the median sharpness."""
    v = np.asarray(values, float)
    return v >= share * float(np.median(v)) if len(v) else np.zeros(0, bool)


def frozen_mask(frames) -> np.ndarray:
    """True where a frame repeats the previous frame's pixels exactly."""
    out, prev = [], None
    for f in frames:
        out.append(prev is not None and prev.shape == f.shape and bool(np.array_equal(prev, f)))
        prev = f
    return np.array(out, bool)


def ffc_mask(stamps_ns: np.ndarray, spans_ns, margin_ns: int = FFC_MARGIN_NS) -> np.ndarray:
    """True for stamps inside any FFC span (start, end) widened by ``margin_ns``."""
    t = np.asarray(stamps_ns, np.int64)
    out = np.zeros(len(t), bool)
    for a, b in spans_ns:
        out |= (t >= int(a) - margin_ns) & (t <= int(b) + margin_ns)
    return out


def _pose(xy: np.ndarray, size) -> np.ndarray:
    """(apparent size, aspect of the spread) of a board's corners, both relative."""
    c = xy - xy.mean(axis=0)
    ev = np.sqrt(np.maximum(np.linalg.eigvalsh(c.T @ c / len(c)), 1e-9))
    return np.array([ev[1] / max(size), ev[0] / ev[1]])


def coverage_greedy(corners: list, imagersize: tuple[int, int], max_frames: int = 40,
                    min_corners: int = 6) -> list[int]:
    """Indices (pick order) of at most ``max_frames`` frames whose boards together cover the image;
    ``corners[k]``: (n, 2) px of frame k's corners (NaN rows ignored) or None."""
    W, H = imagersize
    gx, gy = COVERAGE_GRID
    cells, poses = [], []
    for c in corners:
        xy = None if c is None else np.asarray(c, float)
        xy = None if xy is None else xy[np.isfinite(xy[:, 0])]
        if xy is None or len(xy) < min_corners:
            cells.append(None)
            poses.append(None)
            continue
        ix = np.clip((xy[:, 0] / W * gx).astype(int), 0, gx - 1)
        iy = np.clip((xy[:, 1] / H * gy).astype(int), 0, gy - 1)
        cells.append(np.bincount(iy * gx + ix, minlength=gx * gy))
        poses.append(_pose(xy, (W, H)))
    count = np.zeros(gx * gy)
    chosen: list[int] = []
    while len(chosen) < max_frames:
        best, gain = None, MIN_GAIN
        for k, h in enumerate(cells):
            if h is None or k in chosen:
                continue
            g = float(np.sum(np.minimum(h, np.maximum(CELL_FULL - count, 0)))) / CELL_FULL
            if chosen:
                g += POSE_WEIGHT * min(float(np.linalg.norm(poses[k] - poses[j])) for j in chosen)
            else:
                g += POSE_WEIGHT
            if g > gain:
                best, gain = k, g
        if best is None:
            break
        chosen.append(best)
        count += cells[best]
    return chosen
