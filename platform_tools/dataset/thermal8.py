"""16-bit raw thermal to 8-bit, exactly as the paper's pipeline (FIReStereo, utils.py ``process_image``
with type "firestereo"):

1. when the frame's maximum is below ``clip_above_counts`` (35000): min-max over the whole frame;
   otherwise clip to order statistics of the sorted pixels, ``lower = sorted[round(N * p_low/100)]``
   and ``upper = sorted[round(N * p_high/100) - 1]`` (Python's round), then min-max between them;
2. ``(x - lo) / (hi - lo) * 255.0`` in float64, truncated to uint8 (``astype``, not rounded);
3. CLAHE (clipLimit 2.0, tiles 8x8), then bilateralFilter(d 5, sigmaColor 20, sigmaSpace 15).

The parameters come from ``processing.thermal_8bit``. The result is bit-identical to that
definition (tests/dataset check it against a direct transcription); it is only faster: order
statistics from a 65536-bin histogram instead of a sort (only when the clip applies), and step 2
as a lookup table over the counts between lo and hi, applied by a kernel loaded on the first conversion
(:mod:`.kernels`: compiled ahead of time, or by numba): never with this module, so a process that only plans an
export (the parent, which needs :class:`Params`) never pays numba's import (0.7 s of CPU; docs/dataset.md "Speed").
One deliberate difference: a flat frame
(hi == lo), which the original turns into
NaN casts, becomes all zeros.
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np


@dataclass(frozen=True)
class Params:
    percentile_low: float
    percentile_high: float
    clahe_clip_limit: float
    clahe_tile_grid: int
    bilateral_d: int
    bilateral_sigma_color: float
    bilateral_sigma_space: float
    clip_above_counts: int

    @classmethod
    def from_rig(cls, rig) -> "Params":
        p = rig.desc.processing.thermal_8bit
        return cls(p.percentile_low, p.percentile_high, p.clahe_clip_limit, p.clahe_tile_grid, p.bilateral_d,
                   p.bilateral_sigma_color, p.bilateral_sigma_space, p.clip_above_counts)


_clahe_cache: dict[tuple[float, int], cv2.CLAHE] = {}


def _clahe(p: Params) -> cv2.CLAHE:
    key = (p.clahe_clip_limit, p.clahe_tile_grid)
    if key not in _clahe_cache:
        _clahe_cache[key] = cv2.createCLAHE(clipLimit=p.clahe_clip_limit,
                                            tileGridSize=(p.clahe_tile_grid, p.clahe_tile_grid))
    return _clahe_cache[key]


def bounds(raw: np.ndarray, p: Params) -> tuple[int, int, bool]:
    """(lo, hi, clipped): the counts mapped to 0 and 255, and whether the percentile clip applied."""
    vmax = int(raw.max())
    if vmax < p.clip_above_counts:
        return int(raw.min()), vmax, False
    hist = np.bincount(raw.ravel(), minlength=65536)
    n = raw.size
    cum = np.cumsum(hist)
    k_lo = round(n * p.percentile_low / 100.0)
    k_hi = round(n * p.percentile_high / 100.0) - 1
    # the k-th smallest value (0-based) is the first v with cum[v] > k
    lo = int(np.searchsorted(cum, k_lo, side="right"))
    hi = int(np.searchsorted(cum, k_hi, side="right"))
    return lo, hi, True


def to_8bit_minmax(raw: np.ndarray, p: Params) -> tuple[np.ndarray, tuple[int, int, bool]]:
    """Step 1-2 only: the min-max (with percentile clip) image before CLAHE."""
    raw = np.ascontiguousarray(raw, dtype=np.uint16)
    lo, hi, clipped = bounds(raw, p)
    if hi <= lo:
        return np.zeros(raw.shape, np.uint8), (lo, hi, clipped)
    # the same float64 expression as the original, evaluated once per count value in [lo, hi]
    lut = ((np.arange(lo, hi + 1, dtype=np.float64) - lo) / (hi - lo) * 255.0).astype(np.uint8)
    out = np.empty(raw.shape, np.uint8)
    _kernel()(raw.reshape(-1), lut, lo, hi, out.reshape(-1))
    return out, (lo, hi, clipped)


def _apply(raw, lut, lo, hi, out):
    """out = lut[clip(raw, lo, hi) - lo]: counts at or below lo take lut[0], at or above hi lut[hi - lo]."""
    for i in range(raw.shape[0]):
        v = raw[i]
        out[i] = lut[0] if v <= lo else (lut[hi - lo] if v >= hi else lut[v - lo])


def _kernel():
    """:func:`_apply` compiled (:mod:`.kernels`: the extension built ahead of time, or numba's JIT, cached on disk,
    imported on first use)."""
    from .kernels import get
    return get("apply_lut")


def warm_up() -> None:
    """Load :func:`_apply`'s kernel with the argument types :func:`to_8bit_minmax` passes (uint16 counts, uint8
    lookup table and output, int bounds), and nothing else: no OpenCV call, so no OpenCV thread is started in a
    process that forks the export's workers after warming up (engines.Pool)."""
    _kernel()(np.zeros(4, np.uint16), np.zeros(2, np.uint8), 0, 1, np.empty(4, np.uint8))


def to_8bit(raw: np.ndarray, p: Params) -> tuple[np.ndarray, dict]:
    """The paper's 8-bit image of a raw frame, and what was used (lo, hi counts, whether clipped)."""
    img, (lo, hi, clipped) = to_8bit_minmax(raw, p)
    info = {"lo_counts": lo, "hi_counts": hi, "percentile_clip": clipped}
    if hi <= lo:
        return img, info
    img = _clahe(p).apply(img)
    img = cv2.bilateralFilter(img, p.bilateral_d, p.bilateral_sigma_color, p.bilateral_sigma_space)
    return img, info
