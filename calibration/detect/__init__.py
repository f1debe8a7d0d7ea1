"""Heated-checkerboard corner detection for thermal images.

``detect_corners(image, board=(W, H))`` -> :class:`Detection` with ``corners`` (H*W, 2) in grid
order (NaN where not found) and mrcal ``level`` / ``weight`` per corner. ``load_image(path)`` reads a
16-bit or 8-bit image with one-line errors; ``detect_files`` runs both over many files.
``detect_target(image, board, target)`` picks the detector of a ``--target`` kind
(``detect_marker_board``: the checkerboard with a central marker, calibration/targets).
"""
from .detector import Detection, detect_corners
from .images import ImageError, list_images, load_image
from .batch import detect_files
from .marker_board import detect_marker_board
from .targets import detect_target

__all__ = ["Detection", "detect_corners", "detect_marker_board", "detect_target", "ImageError", "load_image",
           "list_images", "detect_files"]
