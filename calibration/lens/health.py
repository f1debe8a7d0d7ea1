"""Is a lens model usable over the whole image? Two checks any exported model must pass.

A lens model fitted to boards can be fine where the boards were and still be unusable: OPENCV8's
rational radial factor (1 + k1 r^2 + k2 r^4 + k3 r^6) / (1 + k4 r^2 + k5 r^4 + k6 r^6) has a pole where
its denominator reaches zero, and any polynomial model can fold back (its radius stops growing with
the off-axis angle). Where that happens inside the field the camera sees, pixels there map to two rays
or none, undistortion maps go wrong and unprojection jumps branches. So:

- **round trip**: every pixel of the imager (a dense grid, border and corner pixels included) is
  unprojected and projected again; it must come back within ROUND_TRIP_TOL_PX. Where the unprojector
  gives no ray at all, the ray is sought again from the nearest pixel that has one (Newton on
  ``project``): mrcal 2.2's numerical unprojection of OPENCV8 gives up at the odd isolated pixel of a
  healthy lens, and a model is not at fault for its unprojector's solver. Such pixels pass only when a
  ray continuous with its neighbour's projects back within the tolerance (``unproject_retried`` counts
  them); beyond a fold there is no ray to find, so they stay failed;
- **radially monotonic**: along every azimuth, the projected distance from the principal point must
  grow strictly with the off-axis angle theta, from 0 out to the angle the image corners are seen at
  (the model's own corner angle, or larger when the caller knows the field is wider: the angle of the
  observed board corners, a nominal lens). The first angle where it does not is the fold (or pole) angle.

Pure functions of a ``project`` ((..., 3) rays -> (..., 2) pixels) and ``unproject`` ((..., 2) pixels ->
(..., 3) rays) pair, so the same check runs on mrcal's model and on OpenCV reading the exported files.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from calibration.lens.fit import imager_grid

ROUND_TRIP_TOL_PX = 0.01       # unproject -> project must return every pixel within this
ROUND_TRIP_GRID_WIDTH = 81     # 81 x 65 points over a 640 x 512 imager, every border pixel row/column end
N_AZIMUTHS = 72                # every 5 deg, plus the four image corners' own directions
THETA_STEP_RAD = math.radians(0.05)
MAX_THETA_RAD = math.radians(89.0)
#: the retry of a pixel without a ray: Newton steps, the finite-difference step on x/z, y/z, and how far (deg
#: off-axis) the ray found may be from its neighbour's (a ray on another branch is not the same surface)
RETRY_STEPS, RETRY_DIFF, RETRY_MAX_JUMP_DEG = 30, 1e-7, 5.0

Project = Callable[[np.ndarray], np.ndarray]
Unproject = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class LensHealth:
    round_trip_max_px: float          # worst |project(unproject(q)) - q| over the grid (inf: no ray)
    round_trip_bad: int               # grid points beyond ROUND_TRIP_TOL_PX
    round_trip_worst_pixel: tuple[float, float]
    corner_angle_deg: float           # the angle monotonicity was required out to
    fold_angle_deg: float | None      # first angle where the projected radius stops growing; None: none
    fold_azimuth_deg: float | None
    unproject_retried: int = 0        # grid points whose unprojector gave no ray, found from a neighbour

    @property
    def round_trip_ok(self) -> bool:
        return self.round_trip_bad == 0

    @property
    def monotonic_ok(self) -> bool:
        return self.fold_angle_deg is None or self.fold_angle_deg > self.corner_angle_deg

    @property
    def ok(self) -> bool:
        return self.round_trip_ok and self.monotonic_ok

    def problem(self) -> str | None:
        """What is wrong, in one phrase, or None."""
        parts = []
        if not self.monotonic_ok:
            parts.append(f"its radius stops growing at {self.fold_angle_deg:.1f} deg off-axis (azimuth "
                         f"{self.fold_azimuth_deg:.0f} deg), inside the {self.corner_angle_deg:.1f} deg the image "
                         f"corners are seen at: a pole or fold inside the image")
        if not self.round_trip_ok:
            x, y = self.round_trip_worst_pixel
            worst = "no ray" if not math.isfinite(self.round_trip_max_px) else f"{self.round_trip_max_px:.3g} px"
            parts.append(f"{self.round_trip_bad} pixel(s) do not survive unproject -> project within "
                         f"{ROUND_TRIP_TOL_PX} px (worst {worst} at ({x:.0f}, {y:.0f}))")
        return "; ".join(parts) or None

    def summary(self) -> dict:
        return dict(ok=self.ok, round_trip_max_px=self.round_trip_max_px, round_trip_bad=self.round_trip_bad,
                    corner_angle_deg=self.corner_angle_deg, fold_angle_deg=self.fold_angle_deg,
                    unproject_retried=self.unproject_retried, problem=self.problem())


def off_axis_deg(v: np.ndarray) -> np.ndarray:
    """Off-axis angle (deg) of rays (..., 3); NaN for a zero or non-finite ray."""
    v = np.asarray(v, dtype=float)
    n = np.linalg.norm(v, axis=-1)
    ang = np.degrees(np.arctan2(np.hypot(v[..., 0], v[..., 1]), v[..., 2]))
    return np.where(np.isfinite(n) & (n > 0), ang, np.nan)


def round_trip(project: Project, unproject: Unproject, imagersize: tuple[int, int],
               n_width: int = ROUND_TRIP_GRID_WIDTH, *, retried: list | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(grid (N, 2) px, error (N,) px) of unproject -> project over the whole imager; inf where no ray
    projects back to the pixel. A pixel the unprojector gives no ray for is sought again from its nearest
    neighbour with a ray (:func:`ray_from_neighbour`); ``retried``, when given, receives the indices for
    which that found a ray."""
    q = imager_grid(imagersize, n_width).reshape(-1, 2)
    with np.errstate(all="ignore"):
        v = np.asarray(unproject(q), dtype=float).reshape(-1, 3)
        good = np.isfinite(v).all(axis=-1) & (np.linalg.norm(v, axis=-1) > 0)
        err = np.full(len(q), np.inf)
        if good.any():
            q2 = np.asarray(project(np.ascontiguousarray(v[good])), dtype=float).reshape(-1, 2)
            e = np.linalg.norm(q2 - q[good], axis=-1)
            err[good] = np.where(np.isfinite(e), e, np.inf)
        if good.any() and not good.all():
            lost = np.nonzero(~good)[0]
            have = np.nonzero(good & (err <= ROUND_TRIP_TOL_PX))[0]
            if len(have):
                nb = have[np.argmin(np.linalg.norm(q[lost, None] - q[None, have], axis=-1), axis=1)]
                e = ray_from_neighbour(project, q[lost], v[nb])
                err[lost] = e
                if retried is not None:
                    retried.extend(int(i) for i in lost[np.isfinite(e)])
    return q, err


def ray_from_neighbour(project: Project, q: np.ndarray, v0: np.ndarray) -> np.ndarray:
    """Errors (N,) px of the rays Newton finds for pixels ``q`` (N, 2), each started from the ray ``v0`` (N, 3) of
    a neighbouring pixel, as (x/z, y/z); inf where it does not converge within ROUND_TRIP_TOL_PX, or ends more
    than RETRY_MAX_JUMP_DEG off-axis from where it started (not the neighbour's surface)."""
    u = v0[:, :2] / v0[:, 2:3]
    ones = np.ones((len(q), 1))

    def f(u):
        return np.asarray(project(np.ascontiguousarray(np.hstack([u, ones]))), dtype=float).reshape(-1, 2)

    with np.errstate(all="ignore"):
        for _ in range(RETRY_STEPS):
            r = f(u) - q
            J = np.stack([(f(u + RETRY_DIFF * np.eye(2)[k]) - f(u)) / RETRY_DIFF for k in range(2)], axis=-1)
            step = np.linalg.solve(J + 1e-12 * np.eye(2), -r[..., None])[..., 0]
            u = u + np.where(np.isfinite(step), step, 0.0)
        e = np.linalg.norm(f(u) - q, axis=-1)
        jump = np.abs(off_axis_deg(np.hstack([u, ones])) - off_axis_deg(v0))
    return np.where(np.isfinite(e) & (e <= ROUND_TRIP_TOL_PX) & (jump <= RETRY_MAX_JUMP_DEG), e, np.inf)


def fold_angle(project: Project, principal_point: tuple[float, float], theta_max_rad: float,
               n_azimuths: int = N_AZIMUTHS, extra_azimuths_rad: np.ndarray | None = None):
    """(theta_deg, azimuth_deg) of the first off-axis angle (up to ``theta_max_rad``) where the projected
    distance from ``principal_point`` stops growing or is not finite, over every azimuth; (None, None)
    when it grows everywhere."""
    phi = np.linspace(0, 2 * math.pi, n_azimuths, endpoint=False)
    if extra_azimuths_rad is not None:
        phi = np.concatenate([phi, np.asarray(extra_azimuths_rad, dtype=float).ravel()])
    theta = np.arange(0.0, theta_max_rad + THETA_STEP_RAD, THETA_STEP_RAD)
    st, ct = np.sin(theta), np.cos(theta)
    v = np.stack([st[None] * np.cos(phi)[:, None], st[None] * np.sin(phi)[:, None],
                  np.broadcast_to(ct[None], (len(phi), len(theta)))], axis=-1)
    with np.errstate(all="ignore"):
        q = np.asarray(project(np.ascontiguousarray(v.reshape(-1, 3))), dtype=float).reshape(len(phi), len(theta), 2)
        r = np.linalg.norm(q - np.asarray(principal_point, dtype=float), axis=-1)
        grows = np.isfinite(r[:, 1:]) & (np.diff(r, axis=1) > 0)
    if grows.all():
        return None, None
    bad_i, bad_j = np.nonzero(~grows)
    k = int(np.argmin(bad_j))
    return float(np.degrees(theta[bad_j[k] + 1])), float(np.degrees(phi[bad_i[k]]) % 360)


def check(project: Project, unproject: Unproject, imagersize: tuple[int, int],
          principal_point: tuple[float, float], *, min_corner_angle_deg: float = 0.0) -> LensHealth:
    """Both checks of the module docstring. The radius must grow out to the larger of the angle the
    model itself sees the image corners at and ``min_corner_angle_deg`` (e.g. the widest observed
    board corner), plus a degree."""
    retried: list[int] = []
    q, err = round_trip(project, unproject, imagersize, retried=retried)
    w, h = imagersize
    corners = np.array([[0.0, 0.0], [w - 1.0, 0.0], [0.0, h - 1.0], [w - 1.0, h - 1.0]])
    with np.errstate(all="ignore"):
        own = off_axis_deg(np.asarray(unproject(corners), dtype=float))
    own_max = float(np.nanmax(own)) if np.isfinite(own).any() else 0.0
    corner_deg = max(own_max, float(min_corner_angle_deg))
    cx, cy = principal_point
    az = np.arctan2(corners[:, 1] - cy, corners[:, 0] - cx)
    fold, fold_az = fold_angle(project, principal_point, math.radians(min(corner_deg + 1.0, 89.0)),
                               extra_azimuths_rad=az)
    bad = err > ROUND_TRIP_TOL_PX
    i = int(np.argmax(np.where(np.isfinite(err), err, 1e300)))
    return LensHealth(float(err.max()), int(bad.sum()), (float(q[i, 0]), float(q[i, 1])), corner_deg,
                      fold, fold_az, len(retried))


def check_mrcal(lensmodel: str, intrinsics: np.ndarray, imagersize: tuple[int, int], *,
                min_corner_angle_deg: float = 0.0) -> LensHealth:
    """:func:`check` of an mrcal lens through mrcal.project / mrcal.unproject."""
    import mrcal
    intrinsics = np.asarray(intrinsics, dtype=float)

    def unproject(q):
        try:
            return mrcal.unproject(np.ascontiguousarray(q, dtype=float), lensmodel, intrinsics, normalize=True)
        except Exception:          # noqa: BLE001 - mrcal raises plain errors where it cannot invert
            return np.full(np.shape(q)[:-1] + (3,), np.nan)

    return check(lambda v: mrcal.project(np.ascontiguousarray(v, dtype=float), lensmodel, intrinsics),
                 unproject, imagersize, (float(intrinsics[2]), float(intrinsics[3])),
                 min_corner_angle_deg=min_corner_angle_deg)
