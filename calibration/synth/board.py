"""The heated checkerboard, in its own coordinates (metres, z = 0 plane).

Inner corner (i, j) is at (i*s, j*s); the (W+1) x (H+1) squares span [-s, W*s] x [-s, H*s]; a
plain border of half a square surrounds them. The signal is the checker pattern blurred by heat
spreading across square edges: a Gaussian of sigma ``spread``. A Gaussian blur of a product of two
1-D square waves is the product of the two blurred waves, so the blurred board is exact and cheap:
``pattern(u, v) = q_W(u) q_H(v)`` with q a blurred square wave in [-1, 1], 0 on the border.
The top-left square (next to corner (0, 0)) is +1.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import ndtr

BORDER_SQUARES = 0.5


@dataclass(frozen=True)
class Board:
    width: int        # inner corners across (W, as OpenCV's pattern size)
    height: int       # inner corners down (H)
    square_m: float

    @property
    def n(self) -> int:
        return self.width * self.height

    def corners(self) -> np.ndarray:
        """(H*W, 3) corner points in grid order (top-left first, horizontal first), metres."""
        j, i = np.mgrid[0:self.height, 0:self.width]
        return np.stack([i.ravel() * self.square_m, j.ravel() * self.square_m, np.zeros(self.n)], axis=1)

    def centre(self) -> np.ndarray:
        return np.array([(self.width - 1) * self.square_m / 2, (self.height - 1) * self.square_m / 2, 0.0])

    def extent(self) -> tuple[float, float, float, float]:
        """(u0, u1, v0, v1): the physical board, border included."""
        s, b = self.square_m, BORDER_SQUARES * self.square_m
        return (-s - b, self.width * s + b, -s - b, self.height * s + b)

    def inside(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        u0, u1, v0, v1 = self.extent()
        return (u >= u0) & (u <= u1) & (v >= v0) & (v <= v1)

    def pattern(self, u: np.ndarray, v: np.ndarray, spread_m: float) -> np.ndarray:
        """The heat-spread checker signal in [-1, 1] at board points (u, v) (metres)."""
        return _blurred_wave(u, self.width, self.square_m, spread_m) * \
            _blurred_wave(v, self.height, self.square_m, spread_m)


def _blurred_wave(x: np.ndarray, n_inner: int, s: float, sigma: float) -> np.ndarray:
    """A square wave over n_inner+1 squares starting at -s (+1, -1, ...; 0 outside), blurred by a
    Gaussian of sigma (exact up to the neighbouring edges' tails, sigma is kept below s/6)."""
    sigma = max(min(sigma, s / 6.0), 1e-9)
    k = np.clip(np.rint(x / s) + 1, 0, n_inner + 1)           # nearest edge, at (k-1) s
    left, right = k - 1, k

    def value(region):
        return np.where((region >= 0) & (region <= n_inner), 1.0 - 2.0 * (region % 2), 0.0)

    L, R = value(left), value(right)
    return L + (R - L) * ndtr((x - (k - 1) * s) / sigma)
