"""Rectifying thermal images through a calibrated lens: the lens read from its file (model.py), a
pinhole view of a stated field of view and its remap (rectify.py), the before/after figure."""
from .model import Lens, ModelError, read_lens
from .rectify import Pinhole, before_after, pinhole_for, rectify, remap_tables

__all__ = ["Lens", "ModelError", "read_lens", "Pinhole", "pinhole_for", "remap_tables", "rectify", "before_after"]
