"""OpenCV FileStorage YAML (what cv2.FileStorage reads): camera_matrix and distortion_coefficients
as !!opencv-matrix, the image size, and which OpenCV model the coefficients belong to
(``distortion_model``: ``rational_polynomial`` / ``plumb_bob`` for cv2.undistort and friends,
``fisheye`` for cv2.fisheye.*)."""
from __future__ import annotations

import os
import tempfile

import numpy as np

from .conversions import Representation

OPENCV_MODEL_NAME = {"rational_polynomial": "rational_polynomial", "plumb_bob": "plumb_bob",
                     "equidistant": "fisheye"}


def opencv_yaml(rep: Representation, imagersize: tuple[int, int], *, camera_name: str,
                rms_px: float | None = None) -> str:
    """The file's text, written by cv2.FileStorage itself (so OpenCV is sure to read it back)."""
    import cv2
    fd, tmp = tempfile.mkstemp(suffix=".yaml")
    os.close(fd)
    try:
        fs = cv2.FileStorage(tmp, cv2.FILE_STORAGE_WRITE)
        fs.write("camera_name", camera_name)
        fs.write("image_width", int(imagersize[0]))
        fs.write("image_height", int(imagersize[1]))
        fs.write("distortion_model", OPENCV_MODEL_NAME[rep.family])
        fs.write("camera_matrix", np.asarray(rep.K, dtype=np.float64))
        fs.write("distortion_coefficients", np.asarray(rep.D, dtype=np.float64).reshape(1, -1))
        if rms_px is not None:
            fs.write("reprojection_rms_px", float(rms_px))
        fs.writeComment(rep.note())
        fs.release()
        with open(tmp, encoding="utf-8") as f:
            return f.read()
    finally:
        os.unlink(tmp)
