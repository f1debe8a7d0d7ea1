"""The pair cross-checked with OpenCV's fisheye stereo functions, for a Kannala-Brandt pair.

mrcal has no Kannala-Brandt lens, so a pair calibrated with ``calibrate thermal --solver opencv``
reaches ``calibrate thermal-stereo`` as the OPENCV8 fit each ``thermal.cameramodel`` holds; the exact
lenses are in each camera's ``thermal_opencv.yaml`` (``distortion_model: fisheye``). With those, on
the same shared corners, OpenCV's own path is run beside ours:

- **pose**: ``cv2.fisheye.stereoCalibrate`` with the intrinsics fixed (CALIB_FIX_INTRINSIC), from
  the corners both cameras saw in each view, against our pose (mm, deg);
- **rectification**: ``cv2.fisheye.stereoRectify`` with our pose: its rotations R1, R2 against mrcal's
  rectified frames (deg; split into the baseline direction, which both must agree on, and the roll
  about the baseline, which each library chooses its own way: any roll rectifies);
- **epipolar error**: every shared corner through ``cv2.fisheye.undistortPoints`` (the exact KB lens)
  turned by R1 / R2: the difference of its epipolar-plane angle atan2(y, z) in the two rectified
  frames, in our rectified pixels (the LATLON rows are those angles times the rectified fy), so the
  figure compares with ours; also on OpenCV's own pinhole P1 / P2 rows (what an OpenCV user sees,
  inflated off-centre by the pinhole's 1 / cos^2) and at OpenCV's own pose.

Pure functions over arrays; :func:`read_fisheye` reads a cv2.FileStorage file.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

UNDISTORT_CRITERIA = (3, 200, 1e-12)     # cv2.TERM_CRITERIA_COUNT | EPS, as calibration/formats/readback.py


class FisheyeFileError(ValueError):
    """A file that is not an OpenCV fisheye camera; ``str()`` names it and what is wrong."""


@dataclass(frozen=True)
class Fisheye:
    K: np.ndarray                 # 3x3
    D: np.ndarray                 # (4,) k1..k4
    size: tuple[int, int]         # (W, H)


def read_fisheye(path: Path) -> Fisheye:
    """An OpenCV fisheye camera from a cv2.FileStorage YAML (``calibrate thermal``'s thermal_opencv.yaml):
    camera_matrix, distortion_coefficients (4), distortion_model fisheye, image_width, image_height."""
    import cv2
    path = Path(path)
    if not path.is_file():
        raise FisheyeFileError(f"{path}: no such file")
    try:
        fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    except cv2.error:
        raise FisheyeFileError(f"{path}: not a cv2.FileStorage file") from None
    try:
        model = fs.getNode("distortion_model").string()
        K, D = fs.getNode("camera_matrix").mat(), fs.getNode("distortion_coefficients").mat()
        size = (int(fs.getNode("image_width").real()), int(fs.getNode("image_height").real()))
    finally:
        fs.release()
    if model != "fisheye":
        raise FisheyeFileError(f"{path}: distortion_model {model or '(none)'}, not fisheye: give the "
                               f"thermal_opencv.yaml of `calibrate thermal --solver opencv`")
    if K is None or K.shape != (3, 3) or D is None or D.size != 4 or min(size) <= 0:
        raise FisheyeFileError(f"{path}: needs camera_matrix (3x3), 4 distortion_coefficients, image_width "
                               f"and image_height")
    return Fisheye(np.asarray(K, float), np.asarray(D, float).ravel(), size)


def angle_deg(R: np.ndarray) -> float:
    return float(np.degrees(np.arccos(np.clip((np.trace(R) - 1) / 2, -1.0, 1.0))))


def _shared(q_left: np.ndarray, q_right: np.ndarray, points_m: np.ndarray):
    """Per view, the corners seen in both: (object points, left pixels, right pixels) lists."""
    op, il, ir = [], [], []
    for a, b in zip(q_left, q_right):
        ok = np.isfinite(a[:, 0]) & np.isfinite(b[:, 0])
        if ok.sum() >= 6:
            op.append(points_m[ok].reshape(-1, 1, 3).astype(np.float64))
            il.append(a[ok].reshape(-1, 1, 2).astype(np.float64))
            ir.append(b[ok].reshape(-1, 1, 2).astype(np.float64))
    return op, il, ir


def opencv_pose(left: Fisheye, right: Fisheye, q_left, q_right, points_m) -> tuple[np.ndarray, np.ndarray]:
    """(R, T) (right camera from left, T metres) by cv2.fisheye.stereoCalibrate, intrinsics fixed."""
    import cv2
    op, il, ir = _shared(q_left, q_right, points_m)
    flags = cv2.fisheye.CALIB_FIX_INTRINSIC | cv2.fisheye.CALIB_FIX_SKEW
    crit = (cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, 200, 1e-12)
    out = cv2.fisheye.stereoCalibrate(op, il, ir, left.K.copy(), left.D.reshape(4, 1).copy(), right.K.copy(),
                                      right.D.reshape(4, 1).copy(), left.size, flags=flags, criteria=crit)
    R, T = out[5], out[6]
    return np.asarray(R, float), np.asarray(T, float).ravel()


def opencv_rectify(left: Fisheye, right: Fisheye, R: np.ndarray, T: np.ndarray):
    """(R1, R2, P1, P2) of cv2.fisheye.stereoRectify (zero disparity, balance 0)."""
    import cv2
    R1, R2, P1, P2, _ = cv2.fisheye.stereoRectify(left.K, left.D.reshape(4, 1), right.K, right.D.reshape(4, 1),
                                                  left.size, np.asarray(R, float), np.asarray(T, float).reshape(3, 1),
                                                  flags=cv2.CALIB_ZERO_DISPARITY)
    return R1, R2, P1, P2


def _rectified(cam: Fisheye, q: np.ndarray, R: np.ndarray, P: np.ndarray | None) -> np.ndarray:
    import cv2
    x = cv2.fisheye.undistortPoints(q.reshape(-1, 1, 2).astype(np.float64), cam.K, cam.D.reshape(4, 1), R=R,
                                    P=P, criteria=UNDISTORT_CRITERIA)
    return x.reshape(-1, 2)


def _rows(left: Fisheye, right: Fisheye, q_left, q_right, rect, px_per_rad: float) -> dict:
    """Epipolar differences of the shared corners through OpenCV's rectification ``rect`` (R1, R2, P1, P2):
    plane angles (in px at ``px_per_rad``) and OpenCV's own pinhole rows."""
    from .rectify import epipolar_stats
    R1, R2, P1, P2 = rect
    a, b = np.asarray(q_left).reshape(-1, 2), np.asarray(q_right).reshape(-1, 2)
    ok = np.isfinite(a[:, 0]) & np.isfinite(b[:, 0])
    na, nb = _rectified(left, a[ok], R1, None), _rectified(right, b[ok], R2, None)
    plane = px_per_rad * (np.arctan(na[:, 1]) - np.arctan(nb[:, 1]))
    pa, pb = _rectified(left, a[ok], R1, P1), _rectified(right, b[ok], R2, P2)
    return {"rows": epipolar_stats(plane), "pinhole_rows": epipolar_stats(pa[:, 1] - pb[:, 1])}


def cross_check(left: Fisheye, right: Fisheye, q_left: np.ndarray, q_right: np.ndarray, points_m: np.ndarray,
                rt_right_left: np.ndarray, rectified, epipolar_ours: dict) -> dict:
    """OpenCV's fisheye stereo path beside ours (module docstring). ``q_left``, ``q_right`` (N, M, 2) the
    shared views' corners (NaN where not seen), ``points_m`` (M, 3) the board; ``rt_right_left`` our pose
    (mrcal rt, metres); ``rectified`` our (left, right) rectified mrcal models (reference: the left
    camera); ``epipolar_ours`` our epipolar statistics. A stage OpenCV cannot do is named in ``errors``."""
    import cv2
    import mrcal
    R = mrcal.R_from_r(np.asarray(rt_right_left[:3], float))
    T = np.asarray(rt_right_left[3:], float)
    px_per_rad = float(rectified[0].intrinsics()[1][1]) * (1.0 if "LATLON" in rectified[0].intrinsics()[0] else
                                                            float("nan"))
    out: dict = {"lenses": "Kannala-Brandt (cv2.fisheye), exact", "errors": [], "epipolar_ours": epipolar_ours}
    R_rect_l = rectified[0].extrinsics_Rt_fromref()[:3]
    R_rect_r = rectified[1].extrinsics_Rt_fromref()[:3] @ R.T      # right camera -> its rectified frame
    try:
        rect = opencv_rectify(left, right, R, T)
    except cv2.error as exc:
        out["errors"].append(f"cv2.fisheye.stereoRectify: {str(exc).strip().splitlines()[-1]}")
        return out
    R1, R2 = rect[0], rect[1]
    D1, D2 = R1 @ R_rect_l.T, R2 @ R_rect_r.T        # OpenCV's rectified frame from ours, each camera
    x_l = np.degrees(np.arccos(np.clip(R1[0] @ R_rect_l[0], -1, 1)))
    out["rectification"] = {
        "rotation_left_deg": angle_deg(D1), "rotation_right_deg": angle_deg(D2),
        "baseline_axis_deg": float(x_l),
        "roll_about_baseline_deg": float(np.degrees(np.arctan2(D1[2, 1], D1[1, 1]))),
        "left_vs_right_difference_deg": angle_deg(D1 @ D2.T)}
    out["epipolar_opencv_rectification"] = _rows(left, right, q_left, q_right, rect, px_per_rad)
    try:
        R_cv, T_cv = opencv_pose(left, right, q_left, q_right, points_m)
    except cv2.error as exc:
        out["errors"].append(f"cv2.fisheye.stereoCalibrate: {str(exc).strip().splitlines()[-1]}")
        return out
    out["pose"] = {"translation_mm": float(1000 * np.linalg.norm(T_cv - T)),
                   "rotation_deg": angle_deg(R_cv @ R.T),
                   "baseline_mm": float(1000 * np.linalg.norm(T_cv)),
                   "rt_right_left": [float(x) for x in np.concatenate([mrcal.r_from_R(R_cv), T_cv])]}
    try:
        out["epipolar_opencv_pose"] = _rows(left, right, q_left, q_right, opencv_rectify(left, right, R_cv, T_cv),
                                            px_per_rad)
    except cv2.error as exc:
        out["errors"].append(f"cv2.fisheye.stereoRectify at OpenCV's pose: {str(exc).strip().splitlines()[-1]}")
    return out
