"""Synthetic thermal images of a heated checkerboard, with exact ground truth.

``render_dataset(out_dir, n, difficulty, board, square, seed, lens=None)`` writes NNN.png (16-bit
counts), truth.cameramodel and truth.json; see docs/calibration-synthetic.md.
"""
from .board import Board
from .dataset import render_dataset
from .difficulty import DIFFICULTIES, LEVELS, Difficulty
from .lens import nominal_thermal_lens

__all__ = ["render_dataset", "Board", "nominal_thermal_lens", "DIFFICULTIES", "LEVELS", "Difficulty"]
