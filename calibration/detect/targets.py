"""One detector per ``--target`` kind (calibration/targets/spec.py says what each target is)."""
from __future__ import annotations

from functools import partial

import numpy as np

from calibration.targets import TargetError, minimum_board, parse_target
from calibration.targets.spec import CIRCLE_KINDS, circle_present

from .circles import detect_circle_grid
from .detector import Detection, detect_corners
from .marker_board import detect_marker_board

DETECTORS = {"checkerboard": detect_corners, "marker-checkerboard": detect_marker_board,
             **{kind: partial(detect_circle_grid, kind=kind) for kind in CIRCLE_KINDS}}


def check_target_board(target: str, board: tuple[int, int]) -> None:
    """TargetError (a ValueError naming --target / --board) for an unknown target or a board it
    cannot have."""
    parse_target(target)
    circle_present(target, board)          # an asymmetric grid's W must be even
    m = minimum_board(target)
    if min(int(board[0]), int(board[1])) < m:
        what = "lattice points" if target in CIRCLE_KINDS else "inner corners"
        raise TargetError(f"--board {board[0]}x{board[1]}: a {target} needs at least {m}x{m} {what}")


def detect_target(image: np.ndarray, board: tuple[int, int], target: str = "checkerboard") -> Detection:
    """The ``target``'s corners in ``image`` (grid order, NaN where not found or absent)."""
    check_target_board(target, board)
    return DETECTORS[target](image, board)
