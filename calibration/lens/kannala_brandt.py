"""The Kannala-Brandt fisheye projection (OpenCV cv2.fisheye, ROS ``equidistant``, Kalibr
``pinhole-equi``), which mrcal 2.2 does not have: params = (fx, fy, cx, cy, k1, k2, k3, k4),

    theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8)
    q = (fx theta_d x / r + cx, fy theta_d y / r + cy),  r = |(x, y)|, theta = atan2(r, z)
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from calibration.lens.fit import LensFit, imager_grid

NAME = "KANNALA_BRANDT"


@dataclass(frozen=True)
class KannalaBrandt:
    """OpenCV's fisheye result (``calibrate thermal --solver opencv``), which an ``mrcal.cameramodel``
    cannot hold: the one camera value of the project besides mrcal's, for this case only. It answers the
    two questions the format writers ask of a camera as a cameramodel does: ``intrinsics()`` ->
    (:data:`NAME`, params (8,): fx fy cx cy px, k1..k4) and ``imagersize()`` -> (W, H) px."""
    params: np.ndarray
    size: tuple[int, int]

    def intrinsics(self) -> tuple[str, np.ndarray]:
        return NAME, np.array(self.params, dtype=float)

    def imagersize(self) -> tuple[int, int]:
        return self.size


def project(v: np.ndarray, params: np.ndarray) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    fx, fy, cx, cy, k1, k2, k3, k4 = params
    r = np.hypot(v[..., 0], v[..., 1])
    th = np.arctan2(r, v[..., 2])
    t2 = th * th
    thd = th * (1 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4))))
    s = np.where(r > 1e-15, thd / np.where(r > 1e-15, r, 1.0), 1.0 / np.where(v[..., 2] != 0, v[..., 2], 1.0))
    return np.stack([fx * s * v[..., 0] + cx, fy * s * v[..., 1] + cy], axis=-1)


def unproject(q: np.ndarray, params: np.ndarray) -> np.ndarray:
    """Unit rays for pixels; theta from theta_d by Newton's method (monotonic over the image)."""
    q = np.asarray(q, dtype=float)
    fx, fy, cx, cy, k1, k2, k3, k4 = params
    d = np.stack([(q[..., 0] - cx) / fx, (q[..., 1] - cy) / fy], axis=-1)
    thd = np.linalg.norm(d, axis=-1)
    th = thd.copy()
    for _ in range(30):
        t2 = th * th
        f = th * (1 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4)))) - thd
        df = 1 + t2 * (3 * k1 + t2 * (5 * k2 + t2 * (7 * k3 + t2 * 9 * k4)))
        th = th - f / np.where(np.abs(df) > 1e-12, df, 1e-12)
    u = np.where(thd[..., None] > 1e-15, d / np.where(thd > 1e-15, thd, 1.0)[..., None], 0.0)
    return np.concatenate([u * np.sin(th)[..., None], np.cos(th)[..., None]], axis=-1)


def fit(unproject_src: Callable[[np.ndarray], np.ndarray], imagersize: tuple[int, int],
        seed_core: np.ndarray, *, n_width: int = 40) -> LensFit:
    """The Kannala-Brandt lens nearest (in pixels, over the whole imager) to another projection."""
    from scipy.optimize import least_squares
    q = imager_grid(imagersize, n_width).reshape(-1, 2)
    v = np.asarray(unproject_src(q), dtype=float)
    ok = np.isfinite(v).all(axis=-1)
    q, v = q[ok], v[ok]
    x0 = np.concatenate([np.asarray(seed_core, dtype=float)[:4], np.zeros(4)])
    sol = least_squares(lambda p: (project(v, p) - q).ravel(), x0, method="lm", x_scale="jac")
    dist = np.linalg.norm(project(v, sol.x) - q, axis=-1)
    return LensFit(NAME, sol.x, float(np.sqrt(np.mean(dist ** 2))), float(dist.max()))
