"""Calibration targets: what each ``--target`` is, in its own coordinates (the one description the
renderer and the detectors share). ``parse_target(name)`` -> the kind; ``marker_block(board)`` the
corners a central marker hides."""
from .spec import (MARKER_DOT_RADIUS_SQUARES, MARKER_HALF_SQUARES, TARGET_KINDS, TargetError, marker_block,
                   marker_centre, minimum_board, parse_target)

__all__ = ["TARGET_KINDS", "TargetError", "parse_target", "marker_centre", "marker_block", "minimum_board",
           "MARKER_HALF_SQUARES", "MARKER_DOT_RADIUS_SQUARES"]
