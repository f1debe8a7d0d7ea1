"""OPENCV8 from a radial profile, by linear least squares: deterministic, no iteration.

A radially symmetric lens maps a ray at off-axis angle theta to the normalised distorted radius
r_d(theta) (pixels / f). OPENCV8 with zero tangential terms maps the pinhole radius r_u = tan(theta) to

    r_d = r_u (1 + k1 r_u^2 + k2 r_u^4 + k3 r_u^6) / (1 + k4 r_u^2 + k5 r_u^4 + k6 r_u^6)

which, multiplied out, is linear in k1..k6: r_d (1 + k4 r2 + k5 r4 + k6 r6) = r_u (1 + k1 r2 + k2 r4 + k3 r6).
Its rational terms have a valley of near-equal fits (numerator and denominator growing together); an
iterative pixel fit ends anywhere along it, depending on rounding, while this linear solve has one answer
for one profile. Used for the synthetic images' lens (calibration/synth/lens.py) and to seed the solver's
OPENCV8 from its stereographic presolve (calibration/intrinsics/mrcal_solver.py).
"""
from __future__ import annotations

import math
from typing import Callable

import numpy as np

FIT_MARGIN = 1.08          # fit the profile to this factor past the image corner's angle
MAX_ANGLE_RAD = math.radians(85.0)
N_SAMPLES = 400


def rational_terms(theta: np.ndarray, rd: np.ndarray) -> np.ndarray:
    """The OPENCV8 distortion terms (8,) = k1 k2 p1 p2 k3 k4 k5 k6 (p1 = p2 = 0) whose radial profile is
    nearest to ``rd`` (normalised radius, (N,)) at the angles ``theta`` (radians, (N,)): the linear form of
    the module docstring, each row weighted by 1 / (1 + r_u^2) to bring its residual back to pixel scale."""
    ru = np.tan(theta)
    r2 = ru ** 2
    A = np.stack([ru * r2, ru * r2 ** 2, ru * r2 ** 3, -rd * r2, -rd * r2 ** 2, -rd * r2 ** 3], axis=1)
    b = rd - ru
    w = 1.0 / (1.0 + r2)
    k1, k2, k3, k4, k5, k6 = np.linalg.lstsq(A * w[:, None], b * w, rcond=None)[0]
    return np.array([k1, k2, 0.0, 0.0, k3, k4, k5, k6])


def rational_factor(k: np.ndarray, r2: np.ndarray) -> np.ndarray:
    """r_d / r_u of OPENCV8 terms ``k`` (8,) at r_u^2 = ``r2``."""
    return (1 + k[0] * r2 + k[1] * r2 ** 2 + k[4] * r2 ** 3) / (1 + k[5] * r2 + k[6] * r2 ** 2 + k[7] * r2 ** 3)


def corner_radius(core: np.ndarray, imagersize: tuple[int, int]) -> float:
    """The largest normalised radius of the imager's four corner pixels, for a core (fx, fy, cx, cy) in px."""
    fx, fy, cx, cy = (float(x) for x in core[:4])
    w, h = imagersize
    return max(math.hypot((x - cx) / fx, (y - cy) / fy) for x in (0.0, w - 1.0) for y in (0.0, h - 1.0))


def opencv8_from_profile(core: np.ndarray, imagersize: tuple[int, int],
                         profile: Callable[[np.ndarray], np.ndarray],
                         theta_max_rad: float) -> np.ndarray:
    """OPENCV8 intrinsics (12,) with the core (fx, fy, cx, cy, px) and the radial ``profile`` (theta rad ->
    normalised radius, vectorised) fitted over theta in (0, ``theta_max_rad`` * FIT_MARGIN], capped at 85 deg."""
    th_max = min(theta_max_rad * FIT_MARGIN, MAX_ANGLE_RAD)
    theta = np.linspace(1e-4, th_max, N_SAMPLES)
    return np.concatenate([np.asarray(core, dtype=float)[:4], rational_terms(theta, profile(theta))])


def opencv8_from_stereographic(core: np.ndarray, imagersize: tuple[int, int]) -> np.ndarray:
    """The OPENCV8 (12,) nearest to mrcal's LENSMODEL_STEREOGRAPHIC with this core (r_d = 2 tan(theta / 2)),
    over the imager: the solver's seed for a fisheye."""
    theta_corner = 2.0 * math.atan(corner_radius(core, imagersize) / 2.0)
    return opencv8_from_profile(core, imagersize, lambda th: 2.0 * np.tan(th / 2.0), theta_corner)
