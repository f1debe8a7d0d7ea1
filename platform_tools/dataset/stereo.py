"""Depth of the ZED left image computed from the left/right pair, for recordings without a depth topic (the released
TartanRGBT stack records none: the paper computed depth offline from the stereo pair).

The built-in method (``stereo``) runs on the CPU: both images are rectified with the pair's calibration
(:class:`StereoCalibration`: the ZED left and right models with their poses, from the bag's factory camera_info or
the calibration in use), OpenCV's StereoSGBM computes the disparity of the left image and, on the mirrored pair,
the right image's; a left pixel keeps its disparity only when the right image's disparity at its match agrees
within ``LR_MAX_DIFF_PX`` (the left-right consistency check). Its confidence is 1 - |dL - dR| / LR_MAX_DIFF_PX
(0 where the check fails or SGBM has no disparity); depth below ``MIN_CONFIDENCE`` is NaN, so registration
never splats it.

Depth is returned as the ZED publishes it: Z in the (unrectified) left optical frame, metres, one value per pixel of
the left image as recorded; the rectified disparity is sampled at each left pixel's rectified position.

**Plug-in** (learned stereo, e.g. FoundationStereo on a GPU): ``--depth module:function`` names a function

    function(left: np.ndarray, right: np.ndarray, calib: StereoCalibration) -> (depth_m, confidence)

``left``/``right``: (H, W, 3) uint8 BGR as recorded; ``depth_m``: (H, W) float, Z in the left optical frame in
metres at each left pixel (NaN or <= 0: none); ``confidence``: (H, W) float in [0, 1] (pixels below
MIN_CONFIDENCE are dropped). ``calib.rectify(left, right)`` gives the rectified pair and
``calib.depth_from_disparity(disparity)`` turns a disparity of the rectified left image (px) back into that depth,
so a wrapper around a network that takes a rectified pair is a few lines. The module must be importable in every
worker (on ``PYTHONPATH``).
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass

import numpy as np

#: left-right consistency: the largest disagreement (px) between the two disparities
LR_MAX_DIFF_PX = 1.0
#: depth with a lower confidence is dropped (NaN)
MIN_CONFIDENCE = 0.5
#: how depth can come: the recorded topic, the built-in SGBM, or "module:function"
BUILT_IN = ("auto", "recorded", "stereo")


class StereoError(Exception):
    """Stereo depth that cannot be computed as asked (a plug-in that does not load or answers wrongly); one line."""


def _opencv(model, what: str) -> tuple[np.ndarray, np.ndarray]:
    """(K (3, 3), distortion (N,)) in OpenCV's terms of an mrcal model."""
    lens, k = model.intrinsics()
    K = np.array([[k[0], 0, k[2]], [0, k[1], k[3]], [0, 0, 1.0]])
    if lens == "LENSMODEL_PINHOLE":
        return K, np.zeros(5)
    if lens in ("LENSMODEL_OPENCV4", "LENSMODEL_OPENCV5", "LENSMODEL_OPENCV8"):
        return K, np.asarray(k[4:], float)
    raise StereoError(f"{what}: lens model {lens}: stereo rectification takes PINHOLE or OPENCV4/5/8")


@dataclass
class StereoCalibration:
    """The ZED pair at the recorded size: ``left``, ``right`` (``mrcal.cameramodel``, posed in one frame)."""
    left: object
    right: object
    what: str = "stereo pair"

    def __post_init__(self):
        import cv2
        import mrcal
        from platform_tools.rig.cameras import imagersize
        self.size = tuple(int(x) for x in imagersize(self.left))
        if tuple(int(x) for x in imagersize(self.right)) != self.size:
            raise StereoError(f"{self.what}: the left and right models are of different sizes")
        K1, D1 = _opencv(self.left, self.what)
        K2, D2 = _opencv(self.right, self.what)
        rt = mrcal.compose_rt(self.right.extrinsics_rt_fromref(), mrcal.invert_rt(self.left.extrinsics_rt_fromref()))
        R, T = mrcal.R_from_r(rt[:3]), rt[3:].astype(float)
        self.baseline_m = float(np.linalg.norm(T))
        if self.baseline_m <= 0:
            raise StereoError(f"{self.what}: the left and right cameras are at the same place (no baseline)")
        self.R1, self.R2, self.P1, self.P2, *_ = cv2.stereoRectify(K1, D1, K2, D2, self.size, R, T, alpha=0,
                                                                   flags=cv2.CALIB_ZERO_DISPARITY)
        W, H = self.size
        self.maps = [cv2.initUndistortRectifyMap(K, D, Rr, P, self.size, cv2.CV_32FC1)
                     for K, D, Rr, P in ((K1, D1, self.R1, self.P1), (K2, D2, self.R2, self.P2))]
        u, v = np.meshgrid(np.arange(W, dtype=np.float64), np.arange(H, dtype=np.float64))
        q = cv2.undistortPoints(np.stack([u, v], -1).reshape(-1, 1, 2), K1, D1, R=self.R1, P=self.P1)
        #: where each recorded left pixel lies in the rectified left image
        self.left_in_rect = q.reshape(H, W, 2).astype(np.float32)
        self.f = float(self.P1[0, 0])
        self.c = (float(self.P1[0, 2]), float(self.P1[1, 2]))
        self.fB = float(-self.P2[0, 3])      # f * baseline (m px)

    def rectify(self, left: np.ndarray, right: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        import cv2
        return tuple(cv2.remap(img, mx, my, cv2.INTER_LINEAR) for img, (mx, my) in zip((left, right), self.maps))

    def depth_from_disparity(self, disparity: np.ndarray, confidence: np.ndarray | None = None):
        """Z (m, left optical frame) at each recorded left pixel from a disparity of the rectified left image (px;
        <= 0 or NaN: none); with ``confidence`` (rectified), also it at each recorded pixel."""
        import cv2
        mx, my = self.left_in_rect[..., 0], self.left_in_rect[..., 1]
        d = cv2.remap(np.nan_to_num(disparity.astype(np.float32), nan=0.0), mx, my, cv2.INTER_NEAREST,
                      borderValue=0.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            zr = np.where(d > 0, self.fB / d, np.nan)
        # the rectified point, back into the left optical frame: p = R1^T p_rect
        x = (mx - self.c[0]) / self.f * zr
        y = (my - self.c[1]) / self.f * zr
        z = (self.R1[0, 2] * x + self.R1[1, 2] * y + self.R1[2, 2] * zr).astype(np.float32)
        if confidence is None:
            return z
        conf = cv2.remap(confidence.astype(np.float32), mx, my, cv2.INTER_NEAREST, borderValue=0.0)
        return z, np.where(np.isfinite(z), conf, 0.0).astype(np.float32)


def _matcher(width: int, num_disparities: int | None):
    import cv2
    n = num_disparities or max(16, min(256, (width // 4) // 16 * 16))
    block = 5
    return cv2.StereoSGBM_create(minDisparity=0, numDisparities=n, blockSize=block, P1=8 * 3 * block ** 2,
                                 P2=32 * 3 * block ** 2, uniquenessRatio=10, speckleWindowSize=100,
                                 speckleRange=2, disp12MaxDiff=-1, mode=cv2.STEREO_SGBM_MODE_SGBM_3WAY)


def sgbm_disparity(left_rect: np.ndarray, right_rect: np.ndarray, num_disparities: int | None = None):
    """(disparity of the left image (px, NaN: none or inconsistent), confidence in [0, 1]) of a rectified pair:
    SGBM both ways and the left-right consistency check."""
    m = _matcher(left_rect.shape[1], num_disparities)
    dl = m.compute(left_rect, right_rect).astype(np.float32) / 16.0
    dr = m.compute(np.ascontiguousarray(right_rect[:, ::-1]), np.ascontiguousarray(left_rect[:, ::-1]))
    dr = dr[:, ::-1].astype(np.float32) / 16.0          # disparity of each right pixel (its match is x + d)
    H, W = dl.shape
    ok = dl > 0
    xs = np.arange(W)[None, :] - np.rint(np.where(ok, dl, 0)).astype(np.int64)
    ok &= xs >= 0
    other = dr[np.arange(H)[:, None], np.clip(xs, 0, W - 1)]
    diff = np.abs(dl - other)
    ok &= (other > 0) & (diff <= LR_MAX_DIFF_PX)
    conf = np.where(ok, 1.0 - diff / (2 * LR_MAX_DIFF_PX), 0.0).astype(np.float32)
    return np.where(ok, dl, np.nan).astype(np.float32), conf


def sgbm_depth(left: np.ndarray, right: np.ndarray, calib: StereoCalibration):
    """The built-in method (the plug-in signature): rectify, SGBM with the consistency check, back to depth."""
    lr, rr = calib.rectify(left, right)
    disp, conf = sgbm_disparity(lr, rr)
    return calib.depth_from_disparity(disp, conf)


def load_plugin(spec: str):
    """The function ``module:function`` names; :class:`StereoError` (one line) when it does not load."""
    mod, sep, fn = spec.partition(":")
    if not sep or not mod or not fn:
        raise StereoError(f"--depth {spec!r}: expected recorded, stereo or module:function")
    try:
        f = getattr(importlib.import_module(mod), fn)
    except ImportError as exc:
        raise StereoError(f"--depth {spec}: cannot import {mod} ({exc})") from None
    except AttributeError:
        raise StereoError(f"--depth {spec}: {mod} has no {fn}") from None
    if not callable(f):
        raise StereoError(f"--depth {spec}: {fn} is not a function")
    return f


def compute(method: str, left: np.ndarray, right: np.ndarray, calib: StereoCalibration) -> np.ndarray:
    """Depth (m, NaN where none or below MIN_CONFIDENCE) of the left image by ``method`` ("stereo" or a plug-in)."""
    fn = sgbm_depth if method == "stereo" else load_plugin(method)
    out = fn(left, right, calib)
    try:
        depth, conf = (np.asarray(a, np.float32) for a in out)
    except (TypeError, ValueError):
        raise StereoError(f"--depth {method}: expected (depth_m, confidence), got {type(out).__name__}") from None
    if depth.shape != left.shape[:2] or conf.shape != left.shape[:2]:
        raise StereoError(f"--depth {method}: depth {depth.shape} / confidence {conf.shape}, the left image "
                          f"{left.shape[:2]}")
    return np.where(conf >= MIN_CONFIDENCE, depth, np.float32(np.nan))
