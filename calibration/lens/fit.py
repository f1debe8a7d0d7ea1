"""Fit one lens model to another projection: the nearest representable model and how far it is.

Used to seed a rich model from a simple one, to express a splined model in a format that has no
splined equivalent (ROS rational_polynomial), and to turn OpenCV's Kannala-Brandt fisheye into an
mrcal model. The fit samples a grid over the whole imager, unprojects it with the source, and
solves for the target intrinsics that project those rays back onto the same pixels (least squares in
pixels, mrcal's analytic gradients).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np


@dataclass(frozen=True)
class LensFit:
    lensmodel: str
    intrinsics: np.ndarray
    rms_px: float      # RMS pixel difference over the fitted grid
    max_px: float      # worst pixel difference over the fitted grid


def imager_grid(imagersize: tuple[int, int], n_width: int = 40) -> np.ndarray:
    """(Ny, Nx, 2) pixel grid covering the whole imager, corners included."""
    w, h = imagersize
    n_height = max(2, int(round(n_width * h / w)))
    x = np.linspace(0, w - 1, n_width)
    y = np.linspace(0, h - 1, n_height)
    return np.stack(np.meshgrid(x, y), axis=-1)


def fit_lensmodel(unproject: Callable[[np.ndarray], np.ndarray], imagersize: tuple[int, int],
                  lensmodel: str, seed: np.ndarray, *, n_width: int = 40,
                  fix_core: bool = False) -> LensFit:
    """Fit ``lensmodel`` so that it maps the rays ``unproject(q)`` back onto q over the imager.

    ``unproject``: (..., 2) pixels -> (..., 3) ray directions of the source projection.
    ``seed``: starting intrinsics of the target (its core at least, zeros for the rest are fine).
    """
    import mrcal
    from scipy.optimize import least_squares

    q = imager_grid(imagersize, n_width).reshape(-1, 2)
    v = np.asarray(unproject(q), dtype=float).reshape(-1, 3)
    ok = np.isfinite(v).all(axis=-1) & (np.linalg.norm(v, axis=-1) > 0)
    q, v = q[ok], v[ok]
    n_params = mrcal.lensmodel_num_params(lensmodel)
    x0 = np.zeros(n_params)
    seed = np.asarray(seed, dtype=float)
    x0[:min(n_params, len(seed))] = seed[:n_params]
    free = np.arange(4 if fix_core else 0, n_params)

    def full(p: np.ndarray) -> np.ndarray:
        x = x0.copy()
        x[free] = p
        return x

    def residual(p: np.ndarray) -> np.ndarray:
        return (mrcal.project(v, lensmodel, full(p)) - q).ravel()

    def jac(p: np.ndarray) -> np.ndarray:
        _, _, dq_di = mrcal.project(v, lensmodel, full(p), get_gradients=True)
        return dq_di.reshape(-1, n_params)[:, free]

    sol = least_squares(residual, x0[free], jac=jac, method="lm", x_scale="jac", max_nfev=400)
    x = full(sol.x)
    d = np.linalg.norm((mrcal.project(v, lensmodel, x) - q), axis=-1)
    return LensFit(lensmodel, x, float(np.sqrt(np.mean(d ** 2))), float(d.max()))


def mrcal_unprojector(lensmodel: str, intrinsics: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    import mrcal
    return lambda q: mrcal.unproject(np.ascontiguousarray(q, dtype=float), lensmodel,
                                     np.asarray(intrinsics, dtype=float), normalize=True)


def robust_unproject(q: np.ndarray, lensmodel: str, intrinsics: np.ndarray) -> np.ndarray:
    """mrcal.unproject, normalised, for pixels where mrcal 2.2's numerical inversion of a rational
    (OPENCV8) model occasionally fails at one isolated pixel (it returns a zero vector while its
    neighbours half a pixel away are fine): there, the mean of the rays of two neighbours on opposite
    sides (exact to second order in the half pixel)."""
    import mrcal
    q = np.ascontiguousarray(q, dtype=float)
    intrinsics = np.asarray(intrinsics, dtype=float)
    v = mrcal.unproject(q, lensmodel, intrinsics, normalize=True)

    def ok(x: np.ndarray) -> np.ndarray:
        return np.isfinite(x).all(axis=-1) & (np.linalg.norm(x, axis=-1) > 0.5)

    for d in ((0.5, 0.0), (0.0, 0.5), (0.5, 0.5), (0.5, -0.5), (1.0, 0.0)):
        bad = ~ok(v)
        if not bad.any():
            break
        d = np.array(d)
        a = mrcal.unproject(np.ascontiguousarray(q[bad] - d), lensmodel, intrinsics, normalize=True)
        b = mrcal.unproject(np.ascontiguousarray(q[bad] + d), lensmodel, intrinsics, normalize=True)
        m = a + b
        good = ok(a) & ok(b)
        fixed = v[bad]
        fixed[good] = m[good] / np.linalg.norm(m[good], axis=-1, keepdims=True)
        v[bad] = fixed
    return v
