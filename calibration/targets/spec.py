"""The calibration targets ``--target`` names, described once for the renderer and the detectors.

- ``checkerboard``: W x H inner corners; corner (i, j) at (i s, j s) on the board; the square
  next to corner (0, 0) (up and left of it) is the "+1" colour (heated).
- ``marker-checkerboard``: the same checkerboard with a central marker over the 2 x 2 squares
  around corner (mi, mj) = ((W - 1) // 2, (H - 1) // 2): a plain square at the board's mean
  temperature (neither square colour) with one dot, radius MARKER_DOT_RADIUS_SQUARES x s, at the
  centre of the marker's top-left quarter, of the colour the checker has there (the other colour
  than the two squares it shares an edge with). The marker fixes
  the board's origin and orientation wherever it is seen, so a partial view with no board edge
  still gets board coordinates. Its own squares are absent: the 3 x 3 corners of the marker
  (|i - mi| <= 1 and |j - mj| <= 1: the centre and the 8 where the marker's rim meets a square
  edge) are never reported.
"""
from __future__ import annotations

import numpy as np

TARGET_KINDS = ("checkerboard", "marker-checkerboard")
MARKER_HALF_SQUARES = 1              # the marker spans +-1 square around its centre corner
MARKER_DOT_RADIUS_SQUARES = 0.3      # the orientation dot, in squares
MARKER_RING = MARKER_HALF_SQUARES + 1  # the marker needs a ring of corners around it on the board


class TargetError(ValueError):
    """A target name or a board size the target cannot have; ``str()`` says which and why."""


def parse_target(name: str) -> str:
    if name not in TARGET_KINDS:
        raise TargetError(f"--target {name}: unknown target; choose one of {', '.join(TARGET_KINDS)}")
    return name


def minimum_board(kind: str) -> int:
    """The fewest inner corners along either axis a ``kind`` target has."""
    return 2 * MARKER_RING + 1 if kind == "marker-checkerboard" else 2


def marker_centre(board: tuple[int, int]) -> tuple[int, int]:
    """(mi, mj): the inner corner at the marker's centre."""
    W, H = int(board[0]), int(board[1])
    if min(W, H) < minimum_board("marker-checkerboard"):
        m = minimum_board("marker-checkerboard")
        raise TargetError(f"--board {W}x{H}: a marker checkerboard needs at least {m}x{m} inner corners "
                          f"(the marker's 3x3 corners and a ring of squares around them)")
    return (W - 1) // 2, (H - 1) // 2


def marker_block(board: tuple[int, int]) -> np.ndarray:
    """(H*W,) bool in grid order: the corners the marker hides (never reported)."""
    W, H = int(board[0]), int(board[1])
    mi, mj = marker_centre(board)
    j, i = np.mgrid[0:H, 0:W]
    return ((np.abs(i - mi) <= MARKER_HALF_SQUARES) & (np.abs(j - mj) <= MARKER_HALF_SQUARES)).ravel()
