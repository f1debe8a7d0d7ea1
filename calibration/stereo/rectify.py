"""Stereo rectification of the solved pair with mrcal (rectified_system, rectification_maps) and the
epipolar error: how far apart the rows of one board corner land in the two rectified views.

mrcal's rectified cameras sit where the input cameras are, turned alike (x along the baseline), with
a transverse equirectangular projection (LENSMODEL_LATLON: even angular spacing, fit for a 95 deg
lens): a point lands on the same rectified row in both views exactly when the pose is right, so the
row difference of matched corners is the pose's (and the lenses') epipolar error, in rectified px.
"""
from __future__ import annotations

import numpy as np


def field_deg(model) -> tuple[float, float]:
    """(horizontal, vertical) angle (deg) between the rays of the image's edge midpoints of ``model``
    (an mrcal.cameramodel): the field its imager sees along its central row and column."""
    import mrcal
    W, H = (int(x) for x in model.imagersize())
    lm, intr = model.intrinsics()
    cx, cy = (W - 1) / 2, (H - 1) / 2
    q = np.array([[-0.5, cy], [W - 0.5, cy], [cx, -0.5], [cx, H - 0.5]])
    v = mrcal.unproject(q, lm, intr, normalize=True)
    ang = lambda a, b: float(np.degrees(np.arccos(np.clip(v[a] @ v[b], -1, 1))))
    return ang(0, 1), ang(2, 3)


def rectified_models(models, az_fov_deg: float | None = None, el_fov_deg: float | None = None):
    """The rectified pair (two mrcal.cameramodel, LENSMODEL_LATLON, in the input models' reference frame)
    of ``models`` (left, right). Fields default to the left camera's own (:func:`field_deg`), the
    resolution to the input's at the centre (mrcal's pixels_per_deg = -1)."""
    import mrcal
    az, el = field_deg(models[0])
    return mrcal.rectified_system(list(models), az_fov_deg=az_fov_deg or az, el_fov_deg=el_fov_deg or el)


def rectification_maps(models, rectified) -> tuple[np.ndarray, np.ndarray]:
    """(left, right) float32 maps (Hr, Wr, 2): the input pixel (x, y) each rectified pixel samples
    (``cv2.remap(image, m, None, cv2.INTER_LINEAR)``)."""
    import mrcal
    maps = mrcal.rectification_maps(list(models), list(rectified))
    return tuple(np.ascontiguousarray(m, dtype=np.float32) for m in maps)


def to_rectified(model, rectified, q: np.ndarray) -> np.ndarray:
    """Rectified pixels (M, 2) of input pixels ``q`` (M, 2) of ``model`` (NaN rows stay NaN). The
    rectified camera shares the input's centre, so turning the ray is exact at any depth."""
    import mrcal
    out = np.full(q.shape, np.nan)
    ok = np.isfinite(q).all(axis=1)
    if not ok.any():
        return out
    v = mrcal.unproject(np.ascontiguousarray(q[ok]), *model.intrinsics())
    Rt = mrcal.compose_Rt(rectified.extrinsics_Rt_fromref(), model.extrinsics_Rt_toref())
    out[ok] = mrcal.project(mrcal.rotate_point_R(Rt[:3], v), *rectified.intrinsics())
    return out


def row_disparity(models, rectified, q_left: np.ndarray, q_right: np.ndarray) -> np.ndarray:
    """(K,) rectified-row difference (left minus right, px) of the corners seen in both views:
    ``q_left``, ``q_right`` (N, M, 2) pixels, NaN where not seen."""
    a = to_rectified(models[0], rectified[0], q_left.reshape(-1, 2))
    b = to_rectified(models[1], rectified[1], q_right.reshape(-1, 2))
    d = a[:, 1] - b[:, 1]
    return d[np.isfinite(d)]


def epipolar_stats(dy: np.ndarray) -> dict:
    """RMS, 99th percentile and worst of |dy| (px), and the count."""
    a = np.abs(np.asarray(dy, float))
    if a.size == 0:
        return {"n": 0, "rms_px": float("nan"), "p99_px": float("nan"), "max_px": float("nan")}
    return {"n": int(a.size), "rms_px": float(np.sqrt(np.mean(a ** 2))), "p99_px": float(np.percentile(a, 99)),
            "max_px": float(a.max())}
