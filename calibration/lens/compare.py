"""Compare a solved lens with the true one: how far apart they project, over the whole image.

Focal length and principal point are compared directly (meaningful when both use the same kind of
model). The projection difference is what matters: a grid of pixels over the whole imager is
unprojected with the truth, rotated by the best-fit rotation between the two cameras (a camera
model's intrinsics cannot pin down its exact orientation, so a pure rotation is not an error; this
is what mrcal's projection_diff does at infinity) and projected with the solved model; the distance
to the original pixel is the error there. Reported: RMS and worst over the whole image and RMS over
its central 80% (the rectangle with a 10% margin on every side).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from calibration.lens.fit import imager_grid

Project = Callable[[np.ndarray], np.ndarray]      # (..., 3) rays -> (..., 2) pixels
Unproject = Callable[[np.ndarray], np.ndarray]    # (..., 2) pixels -> (..., 3) rays

CENTRAL_FRACTION = 0.8
GRID_WIDTH = 64


@dataclass(frozen=True)
class Comparison:
    imagersize: tuple[int, int]
    grid: np.ndarray              # (Ny, Nx, 2) pixels
    diff_px: np.ndarray           # (Ny, Nx) projection difference at each grid pixel
    rotation_deg: float           # size of the best-fit rotation
    rms_px: float
    max_px: float
    central_rms_px: float
    central_max_px: float
    focal_error_px: tuple[float, float] | None
    principal_point_error_px: tuple[float, float] | None

    def summary(self) -> dict:
        return dict(rms_px=self.rms_px, max_px=self.max_px, central80_rms_px=self.central_rms_px,
                    central80_max_px=self.central_max_px, rotation_deg=self.rotation_deg,
                    focal_error_px=self.focal_error_px, principal_point_error_px=self.principal_point_error_px,
                    grid=list(self.grid.shape[:2][::-1]))


def central_mask(grid: np.ndarray, imagersize: tuple[int, int], fraction: float = CENTRAL_FRACTION) -> np.ndarray:
    w, h = imagersize
    mx, my = (1 - fraction) / 2 * (w - 1), (1 - fraction) / 2 * (h - 1)
    return ((grid[..., 0] >= mx) & (grid[..., 0] <= w - 1 - mx) &
            (grid[..., 1] >= my) & (grid[..., 1] <= h - 1 - my))


def best_rotation(v_truth: np.ndarray, q: np.ndarray, project: Project) -> np.ndarray:
    """Rodrigues r minimising |project(R v) - q| in pixels over all grid points: seeded by the
    Procrustes fit of the rays, refined by least squares."""
    import mrcal
    from scipy.optimize import least_squares

    def res(r: np.ndarray) -> np.ndarray:
        return (project(mrcal.rotate_point_r(r, v_truth)) - q).ravel()

    r0 = np.zeros(3)
    sol = least_squares(res, r0, method="lm", x_scale=1e-3)
    return sol.x


def compare(project: Project, unproject_truth: Unproject, imagersize: tuple[int, int], *,
            grid_width: int = GRID_WIDTH, fit_rotation: bool = True,
            core: np.ndarray | None = None, core_truth: np.ndarray | None = None,
            fit_fraction: float | None = None) -> Comparison:
    """Projection difference of a solved lens (``project``) against the truth (``unproject_truth``).
    ``fit_fraction``: fit the rotation only over that central part of the image (as mrcal's
    projection_diff fits it in a focus region), e.g. to compare two solves that both go wrong where
    there is no data; None: over the whole image."""
    import mrcal
    grid = imager_grid(imagersize, grid_width)
    q = grid.reshape(-1, 2)
    v = np.asarray(unproject_truth(q), dtype=float)
    if fit_rotation:
        m = np.ones(len(q), bool) if fit_fraction is None else central_mask(grid, imagersize, fit_fraction).ravel()
        m &= np.isfinite(v).all(axis=-1)
        r = best_rotation(v[m], q[m], project)
    else:
        r = np.zeros(3)
    d = np.linalg.norm(project(mrcal.rotate_point_r(r, v)) - q, axis=-1).reshape(grid.shape[:2])
    d = np.where(np.isfinite(d), d, np.inf)
    cm = central_mask(grid, imagersize)
    fe = pe = None
    if core is not None and core_truth is not None:
        fe = (float(core[0] - core_truth[0]), float(core[1] - core_truth[1]))
        pe = (float(core[2] - core_truth[2]), float(core[3] - core_truth[3]))
    return Comparison(imagersize, grid, d, float(np.degrees(np.linalg.norm(r))),
                      float(np.sqrt(np.mean(d ** 2))), float(d.max()),
                      float(np.sqrt(np.mean(d[cm] ** 2))), float(d[cm].max()), fe, pe)


def compare_models(model, truth, **kw) -> Comparison:
    """Two mrcal.cameramodel: the solved one and the truth (same imager size)."""
    import mrcal
    lm, intr = model.intrinsics()
    lt, it = truth.intrinsics()
    if tuple(model.imagersize()) != tuple(truth.imagersize()):
        raise ValueError(f"imager sizes differ: {tuple(model.imagersize())} vs truth {tuple(truth.imagersize())}")
    return compare(lambda v: mrcal.project(np.ascontiguousarray(v), lm, intr),
                   lambda q: mrcal.unproject(np.ascontiguousarray(q), lt, it, normalize=True),
                   tuple(int(x) for x in truth.imagersize()), core=intr[:4], core_truth=it[:4], **kw)
