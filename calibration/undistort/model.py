"""A calibrated lens read from the files this project writes: an mrcal ``.cameramodel`` (projected
with mrcal.project) or an OpenCV FileStorage YAML with ``camera_matrix``, ``distortion_coefficients``,
``image_width``/``image_height`` and ``distortion_model`` ``fisheye`` (cv2.fisheye.projectPoints),
``rational_polynomial`` or ``plumb_bob`` (cv2.projectPoints), as thermal_opencv.yaml is written
(calibration/formats/opencv_yaml.py). Any other file is a :class:`ModelError` naming it."""
from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

OPENCV_MODELS = ("fisheye", "rational_polynomial", "plumb_bob")
N_COEFFS = {"fisheye": (4,), "plumb_bob": (5,), "rational_polynomial": (8, 12, 14)}


class ModelError(Exception):
    """A model file that cannot be used; ``str()`` names the file and what to do."""


@dataclass(frozen=True)
class Lens:
    """``project``: (n, 3) camera-frame rays -> (n, 2) pixels of the calibrated image;
    ``imagersize`` (W, H); ``how``: which library projects (for the report)."""
    project: Callable[[np.ndarray], np.ndarray]
    imagersize: tuple[int, int]
    how: str


def _mrcal(path: Path) -> Lens:
    import mrcal
    try:
        m = mrcal.cameramodel(str(path))
    except Exception as exc:                      # mrcal raises bare Exceptions on a bad file
        first = (str(exc).strip().splitlines() or ["unreadable"])[0]
        raise ModelError(f"{path}: not a readable mrcal camera model ({first}); give the "
                         f"thermal.cameramodel `calibrate thermal` wrote") from None
    lensmodel, intr = m.intrinsics()
    W, H = (int(x) for x in m.imagersize())

    def project(v):
        return mrcal.project(np.ascontiguousarray(v, dtype=float), lensmodel, intr)
    return Lens(project, (W, H), f"mrcal.project ({lensmodel})")


def _opencv(path: Path) -> Lens:
    import cv2
    text = path.read_bytes()
    if not text.lstrip().startswith(b"%YAML"):
        raise ModelError(f"{path}: not an OpenCV YAML file (no %YAML header); give a .cameramodel or the "
                         f"thermal_opencv.yaml `calibrate thermal` wrote")
    fd, tmp = tempfile.mkstemp(suffix=".yaml")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(text)
        try:
            fs = cv2.FileStorage(tmp, cv2.FILE_STORAGE_READ)
        except cv2.error:
            raise ModelError(f"{path}: OpenCV cannot parse this YAML; give the thermal_opencv.yaml "
                             f"`calibrate thermal` wrote") from None
        K = fs.getNode("camera_matrix").mat()
        D = fs.getNode("distortion_coefficients").mat()
        kind = fs.getNode("distortion_model").string()
        W, H = int(fs.getNode("image_width").real()), int(fs.getNode("image_height").real())
        fs.release()
    finally:
        os.unlink(tmp)
    if K is None or K.shape != (3, 3) or D is None:
        raise ModelError(f"{path}: needs camera_matrix (3x3) and distortion_coefficients")
    if kind not in OPENCV_MODELS:
        raise ModelError(f"{path}: distortion_model {kind or '(missing)'!r}; expected one of "
                         f"{', '.join(OPENCV_MODELS)}")
    D = np.asarray(D, float).ravel()
    if D.size not in N_COEFFS[kind]:
        raise ModelError(f"{path}: {kind} takes {' or '.join(map(str, N_COEFFS[kind]))} distortion "
                         f"coefficients, the file has {D.size}")
    if W <= 0 or H <= 0:
        raise ModelError(f"{path}: needs image_width and image_height")
    K = np.asarray(K, float)
    if not np.all(np.isfinite(K)) or not np.all(np.isfinite(D)) or K[0, 0] <= 0 or K[1, 1] <= 0:
        raise ModelError(f"{path}: camera_matrix or distortion_coefficients not finite / focal length not positive")
    fisheye = kind == "fisheye"
    z = np.zeros(3)

    def project(v):
        v = np.asarray(v, dtype=np.float64).reshape(-1, 1, 3)
        q, _ = cv2.fisheye.projectPoints(v, z, z, K, D) if fisheye else cv2.projectPoints(v, z, z, K, D)
        return q.reshape(-1, 2)
    how = "cv2.fisheye.projectPoints" if fisheye else f"cv2.projectPoints ({kind})"
    return Lens(project, (W, H), how)


def read_lens(path: str | Path) -> Lens:
    """The lens of an mrcal .cameramodel (by suffix) or an OpenCV YAML; ModelError otherwise."""
    path = Path(path)
    if not path.is_file():
        raise ModelError(f"{path}: no such model file; give a .cameramodel or an OpenCV YAML")
    if path.stat().st_size == 0:
        raise ModelError(f"{path}: empty model file")
    if path.suffix == ".cameramodel":
        return _mrcal(path)
    if path.suffix.lower() in (".yaml", ".yml"):
        return _opencv(path)
    raise ModelError(f"{path}: unknown model file type; give a .cameramodel (mrcal) or a .yaml (OpenCV)")
