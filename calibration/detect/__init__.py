"""Heated-checkerboard corner detection for thermal images.

``detect_corners(image, board=(W, H))`` -> :class:`Detection` with ``corners`` (H*W, 2) in grid
order (NaN where not found) and mrcal ``level`` / ``weight`` per corner. ``load_image(path)`` reads a
16-bit or 8-bit image with one-line errors; ``detect_files`` runs both over many files.
"""
from .detector import Detection, detect_corners
from .images import ImageError, list_images, load_image
from .batch import detect_files

__all__ = ["Detection", "detect_corners", "ImageError", "load_image", "list_images", "detect_files"]
