"""Numbers the report and the verdict are made of: where corners were seen (coverage) and how
uncertain the solved projection is across the image (mrcal.projection_uncertainty)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from calibration.lens.fit import imager_grid, robust_unproject
from calibration.lens.compare import central_mask

REGION_NAMES = (("top-left corner", "top edge", "top-right corner"),
                ("left edge", "centre", "right edge"),
                ("bottom-left corner", "bottom edge", "bottom-right corner"))


@dataclass(frozen=True)
class Coverage:
    counts: np.ndarray          # (ny, nx) inlier corners per cell
    regions: np.ndarray         # (3, 3) inlier corners per ninth of the image
    points: np.ndarray          # (M, 2) every inlier corner

    def region_counts(self) -> dict[str, int]:
        return {REGION_NAMES[j][i]: int(self.regions[j, i]) for j in range(3) for i in range(3)}


def coverage(corners: np.ndarray, inlier: np.ndarray, imagersize: tuple[int, int],
             cells: tuple[int, int] = (8, 8)) -> Coverage:
    w, h = imagersize
    pts = corners[inlier].reshape(-1, 2)
    counts, _, _ = np.histogram2d(pts[:, 1], pts[:, 0], bins=[cells[1], cells[0]], range=[[0, h], [0, w]])
    regions, _, _ = np.histogram2d(pts[:, 1], pts[:, 0], bins=[3, 3], range=[[0, h], [0, w]])
    return Coverage(counts.astype(int), regions.astype(int), pts)


@dataclass(frozen=True)
class Uncertainty:
    grid: np.ndarray            # (Ny, Nx, 2) pixels
    stdev_px: np.ndarray        # (Ny, Nx) worst-direction standard deviation at infinity
    central_max_px: float       # worst over the central 80%
    max_px: float               # worst over the whole image
    observed_noise_px: float    # the corner noise mrcal assumed (from the residuals)


def uncertainty(model, n_width: int = 20) -> Uncertainty:
    """Worst-direction projection uncertainty of points at infinity, over a grid covering the image;
    needs a model with optimization_inputs."""
    import mrcal
    lm, intr = model.intrinsics()
    size = tuple(int(x) for x in model.imagersize())
    grid = imager_grid(size, n_width)
    v = robust_unproject(grid, lm, intr)
    s = mrcal.projection_uncertainty(v, model=model, atinfinity=True, what="worstdirection-stdev")
    s = _despike(s, grid, model)
    s = np.where(np.isfinite(s), s, np.inf)
    cm = central_mask(grid, size)
    oi = model.optimization_inputs()
    noise = float(_observed_noise(oi))
    return Uncertainty(grid, s, float(s[cm].max()), float(s.max()), noise)


def _despike(s: np.ndarray, grid: np.ndarray, model) -> np.ndarray:
    """mrcal 2.2's numerical unprojection of a rational model fails at the odd isolated pixel, and
    the uncertainty there comes out as a spike (or NaN) among smooth neighbours. Such a point (more
    than 3x the median of its 3x3 neighbourhood) is evaluated again as the mean over two points half a
    pixel to either side. A real rise (towards an unobserved corner) is smooth and stays."""
    import mrcal
    from scipy.ndimage import median_filter
    from calibration.lens.fit import robust_unproject
    fin = np.where(np.isfinite(s), s, np.nan)
    med = median_filter(np.nan_to_num(fin, nan=np.nanmax(fin) if np.isfinite(fin).any() else 1.0), size=3,
                        mode="nearest")
    spike = ~np.isfinite(s) | (s > 3 * med)
    if not spike.any():
        return s
    lm, intr = model.intrinsics()
    out = s.copy()
    vals = []
    for d in ((-0.5, 0.0), (0.5, 0.0)):
        v = robust_unproject(grid[spike] + np.array(d), lm, intr)
        vals.append(mrcal.projection_uncertainty(v, model=model, atinfinity=True, what="worstdirection-stdev"))
    out[spike] = 0.5 * (vals[0] + vals[1])
    return out


def _observed_noise(oi: dict) -> float:
    """The per-axis corner noise mrcal's uncertainty assumes: the RMS of the inlier residuals."""
    import mrcal
    try:
        x = mrcal.optimizer_callback(**oi, no_jacobian=True)[1]
        n = mrcal.num_measurements_boards(**{k: oi[k] for k in ("lensmodel",)},
                                          Nobservations_board=len(oi["observations_board"]),
                                          calibration_object_width_n=oi["observations_board"].shape[-2],
                                          calibration_object_height_n=oi["observations_board"].shape[-3]) \
            if False else oi["observations_board"][..., 0].size * 2
        xb = x[:n]
        w = oi["observations_board"][..., 2].ravel()
        use = np.repeat(w > 0, 2)
        return float(np.sqrt(np.mean((xb[use] / np.repeat(np.where(w > 0, w, 1), 2)[use]) ** 2)))
    except Exception:
        return float("nan")
