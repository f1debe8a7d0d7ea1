"""Truth lenses of other families than the solver's: radially symmetric lenses projected and
unprojected in closed form here, never through mrcal's or OpenCV's model code (so a bug or an
assumption shared with the solver cannot hide in the test data; tests compare these formulas with
cv2.fisheye, cv2.projectPoints and mrcal as independent references).

A lens is ``fx, fy, cx, cy`` and a radial profile rho(theta): a ray at angle theta off the optical
axis lands at normalised radius rho, i.e. at pixel (cx + fx rho cos(phi), cy + fy rho sin(phi)).
The profiles (``family``, ``coeffs``):

- ``kannala-brandt``  rho = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8)
  (OpenCV's fisheye / ROS equidistant / Kalibr pinhole-equi), coeffs (k1, k2, k3, k4);
- ``stereographic``   rho = 2 tan(theta / 2) (mrcal LENSMODEL_STEREOGRAPHIC), coeffs ();
- ``plumb-bob``       rho = t (1 + k1 t^2 + k2 t^4 + k3 t^6), t = tan(theta) (OpenCV's pinhole with
  radial terms only, mrcal LENSMODEL_OPENCV5 with p1 = p2 = 0), coeffs (k1, k2, k3).

Unprojection inverts the profile by Newton from a table start; it is exact (to 1e-12 rad) up to
:attr:`RadialLens.max_angle_rad`, where the profile stops increasing (or 85 deg).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

MAX_ANGLE_RAD = math.radians(85.0)   # no truth lens is used beyond this off-axis angle
TABLE_SAMPLES = 4000                 # samples of the profile table that starts Newton
NEWTON_STEPS = 8


def _kb(theta: np.ndarray, k: tuple[float, ...]) -> tuple[np.ndarray, np.ndarray]:
    """(rho, d rho / d theta) of the Kannala-Brandt profile, same shape as ``theta``."""
    t2 = theta * theta
    poly = 1 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3])))
    dpoly = 1 + t2 * (3 * k[0] + t2 * (5 * k[1] + t2 * (7 * k[2] + t2 * 9 * k[3])))
    return theta * poly, dpoly


def _stereographic(theta: np.ndarray, k: tuple[float, ...]) -> tuple[np.ndarray, np.ndarray]:
    """(rho, d rho / d theta) of rho = 2 tan(theta / 2)."""
    return 2 * np.tan(theta / 2), 1 / np.cos(theta / 2) ** 2


def _plumb_bob(theta: np.ndarray, k: tuple[float, ...]) -> tuple[np.ndarray, np.ndarray]:
    """(rho, d rho / d theta) of the radial-only pinhole model rho = t (1 + k1 t^2 + k2 t^4 + k3 t^6)."""
    t = np.tan(theta)
    t2 = t * t
    poly = 1 + t2 * (k[0] + t2 * (k[1] + t2 * k[2]))
    dpoly = 1 + t2 * (3 * k[0] + t2 * (5 * k[1] + t2 * 7 * k[2]))
    return t * poly, dpoly * (1 + t2)


PROFILES = {"kannala-brandt": (_kb, 4), "stereographic": (_stereographic, 0), "plumb-bob": (_plumb_bob, 3)}


@dataclass(frozen=True)
class RadialLens:
    """A truth lens (see the module docstring). Hashable: a data set's ray grid is cached by it."""
    family: str
    fx: float
    fy: float
    cx: float
    cy: float
    coeffs: tuple[float, ...]
    size: tuple[int, int]            # (W, H) pixels
    name: str = ""                   # what the lens stands for (e.g. "published Boson 640 + 4.9 mm")

    def __post_init__(self):
        if self.family not in PROFILES:
            raise ValueError(f"unknown lens family {self.family!r}; known: {', '.join(PROFILES)}")
        if len(self.coeffs) != PROFILES[self.family][1]:
            raise ValueError(f"{self.family}: needs {PROFILES[self.family][1]} coefficients, got {len(self.coeffs)}")

    # --- the interface the renderer uses (mrcal.cameramodel's names where they exist)
    def imagersize(self) -> tuple[int, int]:
        return self.size

    def intrinsics(self) -> tuple[str, np.ndarray]:
        """(family, [fx, fy, cx, cy, *coeffs]): what truth.json records."""
        return self.family, np.array([self.fx, self.fy, self.cx, self.cy, *self.coeffs], float)

    def profile(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(rho, d rho / d theta) at off-axis angles ``theta`` (any shape, radians)."""
        fn, _ = PROFILES[self.family]
        return fn(np.asarray(theta, float), self.coeffs)

    @property
    def max_angle_rad(self) -> float:
        """Where the profile stops increasing, or :data:`MAX_ANGLE_RAD`."""
        th = np.linspace(0.0, MAX_ANGLE_RAD, TABLE_SAMPLES)
        _, d = self.profile(th)
        bad = d <= 0
        return float(th[np.argmax(bad)]) if bad.any() else MAX_ANGLE_RAD

    def project(self, p: np.ndarray) -> np.ndarray:
        """Pixels (..., 2) of camera-frame points ``p`` (..., 3) (z forward); points beyond
        :attr:`max_angle_rad` project along the profile's continuation (callers check the angle)."""
        p = np.asarray(p, float)
        rxy = np.hypot(p[..., 0], p[..., 1])
        theta = np.arctan2(rxy, p[..., 2])
        rho, _ = self.profile(theta)
        s = np.where(rxy > 1e-15, rho / np.where(rxy > 1e-15, rxy, 1.0), 0.0)
        return np.stack([self.cx + self.fx * s * p[..., 0], self.cy + self.fy * s * p[..., 1]], axis=-1)

    def theta_of_rho(self, rho: np.ndarray) -> np.ndarray:
        """Off-axis angle (same shape) of normalised radii ``rho``: the profile's inverse (NaN past
        :attr:`max_angle_rad`)."""
        rho = np.asarray(rho, float)
        th_max = self.max_angle_rad
        th_tab = np.linspace(0.0, th_max, TABLE_SAMPLES)
        rho_tab, _ = self.profile(th_tab)
        th = np.interp(rho, rho_tab, th_tab)
        for _ in range(NEWTON_STEPS):
            r, d = self.profile(th)
            th = np.clip(th - (r - rho) / d, 0.0, th_max)
        return np.where(rho <= rho_tab[-1], th, np.nan)

    def unproject(self, q: np.ndarray) -> np.ndarray:
        """Unit observation vectors (..., 3) of pixels ``q`` (..., 2); NaN past :attr:`max_angle_rad`."""
        q = np.asarray(q, float)
        x = (q[..., 0] - self.cx) / self.fx
        y = (q[..., 1] - self.cy) / self.fy
        rho = np.hypot(x, y)
        th = self.theta_of_rho(rho)
        s = np.where(rho > 1e-15, np.sin(th) / np.where(rho > 1e-15, rho, 1.0), 1.0)
        return np.stack([x * s, y * s, np.cos(th)], axis=-1)

    def projection_table(self, step_px: float = 4.0) -> tuple[np.ndarray, np.ndarray]:
        """A dense table for validation: pixels (Ny, Nx, 2) on a ``step_px`` grid over the whole
        imager (pixel centres -0.5 .. W-0.5 edges included) and their unit rays (Ny, Nx, 3)."""
        W, H = self.size
        xs = np.append(np.arange(-0.5, W - 0.5, step_px), W - 0.5)
        ys = np.append(np.arange(-0.5, H - 0.5, step_px), H - 0.5)
        q = np.stack(np.meshgrid(xs, ys), axis=-1)
        return q, self.unproject(q)
