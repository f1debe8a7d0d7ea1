"""Choosing calibration frames from a recording: pure functions over images, stamps and detections
(``select.py``). The bag reading lives in platform_tools.dataset; the command puts the two together."""
from .select import board_sharpness, coverage_greedy, ffc_mask, frozen_mask, sharp_mask, sharpness

__all__ = ["sharpness", "board_sharpness", "sharp_mask", "frozen_mask", "ffc_mask", "coverage_greedy"]
