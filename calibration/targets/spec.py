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
- ``circle-grid``: a symmetric grid of W x H hot discs on a cold board (OpenCV's
  CALIB_CB_SYMMETRIC_GRID with patternSize (W, H)); disc (i, j) centred at (i s, j s), radius
  CIRCLE_RADIUS_SPACING x s. The grid looks the same turned 180 deg (and 90 deg when W == H), so
  its labels follow the image (calibration/detect/circles.py states the rule).
- ``asymmetric-circle-grid``: OpenCV's CALIB_CB_ASYMMETRIC_GRID, given as the lattice the solver
  sees: ``--board WxH`` is W lattice columns (twice the discs per row; W even) by H rows, lattice
  point (i, j) at (i s, j s), and a disc only where i + j is even (row j's discs at i = 2k + j % 2:
  OpenCV's patternSize (W / 2, H) with its squareSize s). The other half of the lattice is absent
  (never reported, as the marker's corners are). Radius CIRCLE_RADIUS_SPACING x s (the discs'
  nearest neighbours are s sqrt 2 apart). With H odd the pattern has no symmetry: every whole view
  has one labelling.
"""
from __future__ import annotations

import numpy as np

TARGET_KINDS = ("checkerboard", "marker-checkerboard", "circle-grid", "asymmetric-circle-grid")
CIRCLE_KINDS = ("circle-grid", "asymmetric-circle-grid")
CIRCLE_RADIUS_SPACING = 0.3          # a disc's radius, in lattice spacings s
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
    """The fewest inner corners (circles, lattice points) along either axis a ``kind`` target has."""
    if kind == "marker-checkerboard":
        return 2 * MARKER_RING + 1
    return 3 if kind in CIRCLE_KINDS else 2


def circle_present(kind: str, board: tuple[int, int]) -> np.ndarray:
    """(H*W,) bool in grid order: the lattice points that carry a disc (all of them for a
    ``circle-grid``; i + j even for an ``asymmetric-circle-grid``). TargetError for an odd W of an
    asymmetric grid."""
    W, H = int(board[0]), int(board[1])
    j, i = np.mgrid[0:H, 0:W]
    if kind == "asymmetric-circle-grid":
        if W % 2:
            raise TargetError(f"--board {W}x{H}: an asymmetric-circle-grid is given as its lattice, W = twice "
                              f"the discs per row (OpenCV's patternSize ({W}, {H}) is --board {2 * W}x{H})")
        return ((i + j) % 2 == 0).ravel()
    return np.ones(W * H, bool)


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
