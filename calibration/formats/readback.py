"""Every exported file read back the way its users read it, and checked over the whole image
(calibration/lens/health.py: unproject -> project within 0.01 px, radius growing out to the corners).

- thermal.cameramodel: mrcal.cameramodel, mrcal.project / mrcal.unproject;
- thermal_opencv.yaml: cv2.FileStorage, then cv2.projectPoints / cv2.undistortPointsIter (rational,
  plumb_bob) or cv2.fisheye.projectPoints / cv2.fisheye.undistortPoints (fisheye);
- thermal_camera_info.yaml and kalibr_camchain.yaml: YAML, then the same OpenCV functions (ROS's
  image_geometry and Kalibr's pinhole-equi are these models).

Unprojection uses OpenCV's iterative undistortion with a strict stopping rule (UNDISTORT_CRITERIA):
with its default 5 iterations cv2.undistortPoints leaves a healthy 95 deg rational lens 3 px wrong in
the image corners, which is a property of that call, not of the model.
"""
from __future__ import annotations

import io
import os
import tempfile

import numpy as np
import yaml

from calibration.lens import health

UNDISTORT_MAX_ITER = 200
UNDISTORT_EPS = 1e-12


def _criteria():
    import cv2
    return (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, UNDISTORT_MAX_ITER, UNDISTORT_EPS)


def opencv_pair(K: np.ndarray, D: np.ndarray, fisheye: bool):
    """(project, unproject) of an OpenCV camera (K, D) through OpenCV's own functions."""
    import cv2
    K = np.asarray(K, dtype=np.float64).reshape(3, 3)
    D = np.asarray(D, dtype=np.float64).ravel()
    z = np.zeros(3)

    def project(v):
        v = np.asarray(v, dtype=np.float64).reshape(-1, 1, 3)
        q, _ = (cv2.fisheye.projectPoints(v, z, z, K, D) if fisheye else cv2.projectPoints(v, z, z, K, D))
        return q.reshape(-1, 2)

    def unproject(q):
        q = np.asarray(q, dtype=np.float64).reshape(-1, 1, 2)
        x = (cv2.fisheye.undistortPoints(q, K, D, criteria=_criteria()) if fisheye else
             cv2.undistortPointsIter(q, K, D, None, None, _criteria())).reshape(-1, 2)
        return np.column_stack([x, np.ones(len(x))])

    return project, unproject


def _from_opencv_yaml(text: str):
    import cv2
    fd, tmp = tempfile.mkstemp(suffix=".yaml")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
        fs = cv2.FileStorage(tmp, cv2.FILE_STORAGE_READ)
        K = fs.getNode("camera_matrix").mat()
        D = fs.getNode("distortion_coefficients").mat()
        fisheye = fs.getNode("distortion_model").string() == "fisheye"
        fs.release()
    finally:
        os.unlink(tmp)
    return K, D, fisheye


def _from_ros(text: str):
    doc = yaml.safe_load(text)
    K = np.array(doc["camera_matrix"]["data"], dtype=float).reshape(3, 3)
    D = np.array(doc["distortion_coefficients"]["data"], dtype=float)
    return K, D, doc["distortion_model"] == "equidistant"


def _from_kalibr(text: str):
    cam = next(iter(yaml.safe_load(text).values()))
    fu, fv, pu, pv = cam["intrinsics"]
    K = np.array([[fu, 0, pu], [0, fv, pv], [0, 0, 1.0]])
    if cam["distortion_model"] != "equidistant":
        raise ValueError(f"kalibr camchain: distortion_model {cam['distortion_model']!r}, expected equidistant")
    return K, np.array(cam["distortion_coeffs"], dtype=float), True


READERS = {"thermal_opencv.yaml": _from_opencv_yaml, "thermal_camera_info.yaml": _from_ros,
           "kalibr_camchain.yaml": _from_kalibr}


def check_file(name: str, text: str, imagersize: tuple[int, int], *,
               min_corner_angle_deg: float = 0.0) -> health.LensHealth:
    """The health of one exported file (``name`` one of READERS or ``*.cameramodel``), read back as its
    users read it."""
    if name.endswith(".cameramodel"):
        import mrcal
        m = mrcal.cameramodel(io.StringIO(text))
        lm, intr = m.intrinsics()
        return health.check_mrcal(lm, intr, imagersize, min_corner_angle_deg=min_corner_angle_deg)
    K, D, fisheye = READERS[name](text)
    project, unproject = opencv_pair(K, D, fisheye)
    return health.check(project, unproject, imagersize, (float(K[0, 2]), float(K[1, 2])),
                        min_corner_angle_deg=min_corner_angle_deg)


def check_files(files: dict[str, str], imagersize: tuple[int, int], *,
                min_corner_angle_deg: float = 0.0) -> dict[str, health.LensHealth]:
    """:func:`check_file` of every lens file among ``files`` ({name: text})."""
    return {name: check_file(name, text, imagersize, min_corner_angle_deg=min_corner_angle_deg)
            for name, text in files.items() if name.endswith(".cameramodel") or name in READERS}
