"""Heated circle grids for the synthetic renderer (calibration/targets/spec.py: ``circle-grid``,
``asymmetric-circle-grid``): hot discs on a cold board, drawn by render.board_layer through any
truth lens like the checkerboard (it reads ``pattern``, ``inside``, ``extent``, ``centre`` and
``corners``).

The signal is -1 on the board and +1 inside a disc; heat spreads across a disc's rim as across a
square's edge: the radial profile ndtr((R - r) / sigma) (exact for a straight edge; sigma is kept
below R / 5). ``corners()`` lists every lattice point (the truth the detector is checked against: a
disc's centre, projected exactly, not the centre of its imaged ellipse); ``present()`` says which
carry a disc. The board's plain border is one spacing wide past the outer discs' centres plus
half a spacing (Board.extent)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import ndtr

from calibration.targets.spec import CIRCLE_KINDS, CIRCLE_RADIUS_SPACING, circle_present

from .board import Board


@dataclass(frozen=True)
class CircleGridBoard(Board):
    """A W x H lattice of spacing ``square_m`` with a disc of ``radius_m`` at every present point
    (``kind``: ``circle-grid`` or ``asymmetric-circle-grid``)."""
    kind: str = "circle-grid"
    radius_m: float = 0.0          # 0: CIRCLE_RADIUS_SPACING x square_m

    def __post_init__(self):
        if self.kind not in CIRCLE_KINDS:
            raise ValueError(f"not a circle grid: {self.kind!r}")
        circle_present(self.kind, (self.width, self.height))      # TargetError for an odd asymmetric W

    @property
    def radius(self) -> float:
        return self.radius_m or CIRCLE_RADIUS_SPACING * self.square_m

    def present(self) -> np.ndarray:
        """(H*W,) bool: lattice points with a disc."""
        return circle_present(self.kind, (self.width, self.height))

    def pattern(self, u: np.ndarray, v: np.ndarray, spread_m: float) -> np.ndarray:
        """-1 on the board, +1 inside a disc, the rim blurred by ``spread_m`` (metres)."""
        s, R = self.square_m, self.radius
        sigma = max(min(spread_m, R / 5.0), 1e-9)
        i = np.clip(np.rint(u / s), 0, self.width - 1)
        j = np.clip(np.rint(v / s), 0, self.height - 1)
        r = np.hypot(u - i * s, v - j * s)
        disc = ndtr((R - r) / sigma)
        if self.kind == "asymmetric-circle-grid":
            # the nearest lattice point may be an empty one: take the nearer of the two discs around it
            disc = np.where((i + j) % 2 == 0, disc, 0.0)
            for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                ii, jj = i + di, j + dj
                ok = (ii >= 0) & (ii < self.width) & (jj >= 0) & (jj < self.height) & ((ii + jj) % 2 == 0)
                d = ndtr((R - np.hypot(u - ii * s, v - jj * s)) / sigma)
                disc = np.maximum(disc, np.where(ok, d, 0.0))
        return 2.0 * disc - 1.0


def circle_board(kind: str, width: int, height: int, spacing_m: float, radius_m: float = 0.0) -> CircleGridBoard:
    """The board the renderer draws for ``--target kind`` (a circle grid), ``--board WxH``."""
    return CircleGridBoard(width, height, spacing_m, kind, radius_m)

