"""The one camera value of the project: an ``mrcal.cameramodel`` (lens model, intrinsics, imager size and
the pose ``rt_fromref``), and the one rule that carries intrinsics to another image size.

Every view of a camera (the nominal models computed from the rig, a calibration, the simulated rig's and the
dataset's cameras at a recorded size, the synthetic images' truth lens) is an ``mrcal.cameramodel``; nothing
else of ours holds fx, fy, cx, cy.

Resizing: an image scaled by ``s`` along an axis maps pixel *centres* as ``q' = (q + 0.5) s - 0.5`` (pixel
``i`` covers ``[i - 0.5, i + 0.5]``, as mrcal and OpenCV count pixels), so ``f' = f s`` and ``c' = (c + 0.5) s
- 0.5``. Distortion terms of every mrcal model act on normalised coordinates and do not change.
"""
from __future__ import annotations

from typing import Sequence

import numpy as np

#: a recording whose images are not the calibrated aspect ratio is cropped or of other cameras
ASPECT_TOLERANCE = 0.01


class ImageSizeError(ValueError):
    """A model cannot be carried to the asked image size (another aspect ratio); one line."""


def scale_intrinsics(intrinsics: Sequence[float], from_size: tuple[int, int],
                     to_size: tuple[int, int]) -> np.ndarray:
    """Intrinsics (N,) of an mrcal model (fx fy cx cy first) for images resized from ``from_size`` (W, H) to
    ``to_size`` (W, H). Returns a new (N,) array; the distortion terms are copied unchanged."""
    k = np.array(intrinsics, dtype=float)
    sx, sy = to_size[0] / from_size[0], to_size[1] / from_size[1]
    k[0] *= sx
    k[1] *= sy
    k[2] = (k[2] + 0.5) * sx - 0.5
    k[3] = (k[3] + 0.5) * sy - 0.5
    return k


def check_aspect(from_size: tuple[int, int], to_size: tuple[int, int], *, what: str) -> None:
    """Raise :class:`ImageSizeError` naming ``what`` when ``to_size`` is not ``from_size`` scaled (one pixel of
    rounding allowed on each axis besides :data:`ASPECT_TOLERANCE`)."""
    (W, H), (w, h) = from_size, to_size
    sx, sy = w / W, h / H
    if abs(sx - sy) > ASPECT_TOLERANCE * sx + 1.0 / W + 1.0 / H:
        raise ImageSizeError(f"{what}: the model is for {W}x{H} images, these are {w}x{h} "
                             f"(aspect {w / h:.3f} vs {W / H:.3f}): cropped images, or other cameras")


def camera_model(lensmodel: str, intrinsics: Sequence[float], imagersize: tuple[int, int],
                 rt_cam_ref: Sequence[float] | None = None):
    """An ``mrcal.cameramodel``; ``rt_cam_ref`` (6,) maps the reference frame into the camera (metres),
    identity when None."""
    import mrcal
    return mrcal.cameramodel(intrinsics=(lensmodel, np.asarray(intrinsics, dtype=float)),
                             imagersize=np.asarray(imagersize, dtype=int),
                             extrinsics_rt_fromref=np.zeros(6) if rt_cam_ref is None
                             else np.asarray(rt_cam_ref, dtype=float))


def scaled(model, size: tuple[int, int], *, what: str = "images"):
    """``model`` (an ``mrcal.cameramodel``) for images of ``size`` (W, H): the same model when the size is
    its own, otherwise a new one with :func:`scale_intrinsics`; raises :class:`ImageSizeError` on another
    aspect ratio."""
    W, H = (int(x) for x in model.imagersize())
    size = (int(size[0]), int(size[1]))
    if size == (W, H):
        return model
    check_aspect((W, H), size, what=what)
    lensmodel, intrinsics = model.intrinsics()
    return camera_model(lensmodel, scale_intrinsics(intrinsics, (W, H), size), size,
                        model.extrinsics_rt_fromref())


def imagersize(model) -> tuple[int, int]:
    """(W, H) of an ``mrcal.cameramodel`` as Python ints."""
    return tuple(int(x) for x in model.imagersize())
