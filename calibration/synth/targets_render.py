"""Boards of the other ``--target`` kinds for the synthetic renderer (render.board_layer reads a
board's ``pattern``, ``inside``, ``extent``, ``centre`` and ``corners``; these keep Board's and
change the pattern).

``MarkerBoard``: the checkerboard with the central marker of calibration/targets/spec.py: a plain
square at the board's mean temperature (signal 0) over the 2 x 2 squares around corner (mi, mj),
with one dot at the centre of its top-left quarter, of the colour the checker has there (the other
colour than the two squares it shares an edge with). Heat spreads across the
marker's rim and the dot's edge as across every square edge: the box is blurred exactly (a product
of two blurred steps, as the squares), the dot by its radial profile ndtr((R - r) / sigma) (exact
for a straight edge; the dot's radius is 5 x the largest sigma used)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import ndtr

from calibration.targets import MARKER_DOT_RADIUS_SQUARES, MARKER_HALF_SQUARES, marker_centre

from .board import Board


def _blurred_box(x: np.ndarray, lo: float, hi: float, sigma: float) -> np.ndarray:
    return ndtr((x - lo) / sigma) - ndtr((x - hi) / sigma)


@dataclass(frozen=True)
class MarkerBoard(Board):
    """A W x H checkerboard with the central marker (corners() still lists all W*H inner corners:
    the truth; calibration.targets.marker_block says which of them the marker hides)."""

    def marker_centre_m(self) -> tuple[float, float]:
        mi, mj = marker_centre((self.width, self.height))
        return mi * self.square_m, mj * self.square_m

    def pattern(self, u: np.ndarray, v: np.ndarray, spread_m: float) -> np.ndarray:
        s = self.square_m
        sigma = max(min(spread_m, s / 6.0), 1e-9)
        cu, cv = self.marker_centre_m()
        half = MARKER_HALF_SQUARES * s
        box = _blurred_box(u, cu - half, cu + half, sigma) * _blurred_box(v, cv - half, cv + half, sigma)
        du, dv = u - (cu - half / 2), v - (cv - half / 2)     # the top-left quarter's centre
        mi, mj = marker_centre((self.width, self.height))
        colour = (1 - 2 * (mi % 2)) * (1 - 2 * (mj % 2))       # the checker's square there (board.py)
        dot = colour * ndtr((MARKER_DOT_RADIUS_SQUARES * s - np.hypot(du, dv)) / sigma)
        return super().pattern(u, v, spread_m) * (1.0 - box) + dot


def target_board(kind: str, width: int, height: int, square_m: float) -> Board:
    """The board object the renderer draws for ``--target kind``."""
    if kind == "marker-checkerboard":
        marker_centre((width, height))          # refuses a board too small for the marker
        return MarkerBoard(width, height, square_m)
    if kind == "checkerboard":
        return Board(width, height, square_m)
    raise ValueError(f"no renderer for target {kind!r}")


def render_views(lens, board: Board, difficulty: str = "real", n: int = 10, seed: int = 0, views=None, only=None):
    """``n`` frames of ``board`` through ``lens`` (in memory, for tests and benches): a list of
    (uint16 image, true corners (W*H, 2) px with NaN out of view, occluded corner mask). ``views``:
    BoardViews to render instead of drawing poses (one image each). ``only``: the frame numbers to
    render (each frame draws from its own generator, so frame k is the same as in the full set)."""
    from platform_tools.rig.cameras import imagersize

    from .difficulty import level
    from .poses import sample_view
    from .render import render_image
    from .sensor import Sensor
    diff = level(difficulty)
    rng = np.random.default_rng(seed)
    W_img, H_img = imagersize(lens)
    sensor = Sensor.make(rng, (H_img, W_img), diff)
    out = []
    for k in range(n if views is None else len(views)):
        if only is not None and k not in only:
            continue
        irng = np.random.default_rng([seed, k])
        view = sample_view(irng, lens, board, diff) if views is None else views[k]
        img, occluded, _ = render_image(irng, lens, board, view, diff, sensor)
        out.append((img, view.corners_px.copy(), occluded))
    return out
