"""8-bit AGC output, as a Boson in 8-bit mode sends it: plateau-limited histogram equalisation of
the 14-bit counts, blended with a linear stretch, per frame.

This is the general scheme FLIR documents for the Boson's AGC (a plateau caps every histogram bin
so that a large uniform background does not take all the grey levels; a linear share keeps some
proportionality); the numbers below are plausible defaults, not FLIR's exact algorithm or settings.
What matters for calibration: the mapping is monotonic but non-linear and changes per frame, and it
quantises to 256 levels, so the detector sees steps of several counts where a faint board has few.
"""
from __future__ import annotations

import numpy as np

PLATEAU_SHARE = 0.007     # a bin holds at most this share of the frame's pixels
LINEAR_SHARE = 0.2        # weight of the linear (min..max) stretch in the blend
TAIL_REJECT = 0.0005      # share of pixels clipped at each end of the linear stretch


def agc8(counts: np.ndarray) -> np.ndarray:
    """uint8 (H, W) of a uint16 frame of counts (H, W)."""
    c = np.asarray(counts)
    lo, hi = int(c.min()), int(c.max())
    if hi <= lo:
        return np.zeros(c.shape, np.uint8)
    hist = np.bincount((c - lo).ravel(), minlength=hi - lo + 1).astype(float)
    hist = np.minimum(hist, PLATEAU_SHARE * c.size)
    cdf = np.cumsum(hist)
    equalised = (cdf - cdf[0]) / max(cdf[-1] - cdf[0], 1.0)
    a, b = np.quantile(c, [TAIL_REJECT, 1 - TAIL_REJECT])
    levels = np.arange(lo, hi + 1, dtype=float)
    linear = np.clip((levels - a) / max(b - a, 1.0), 0.0, 1.0)
    lut = np.rint(255 * ((1 - LINEAR_SHARE) * equalised + LINEAR_SHARE * linear)).astype(np.uint8)
    return lut[c - lo]
