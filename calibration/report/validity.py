"""Where across the image a solved lens can be trusted, and the valid-intrinsics region.

A point of the image is trusted when all of these hold there:

- data: a corner was observed within NO_DATA_RADIUS_PX (a model there is measured, not extrapolated);
- cross-validation: the solutions from two disjoint halves of the images agree within
  MAX_HALVES_DIFF_PX (intrinsics/crossval.py);
- uncertainty: mrcal's projection uncertainty (1 sigma, worst direction, at infinity) is at most
  MAX_UNCERTAINTY_PX (mrcal solver only).

The largest connected trusted area becomes the valid-intrinsics region, a closed polygon in
pixels, written into the .cameramodel as mrcal's ``valid_intrinsics_region`` (mrcal-show-*,
mrcal.is_within_valid_intrinsics_region read it). The untrusted parts are named by ninth of the
image ("the top-left corner") with what failed there, for the verdict, which also reads how much of
the central 80% of the image is trusted (the same rectangle as calibration.lens.compare.central_mask).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from calibration.lens.compare import central_mask
from .analysis import REGION_NAMES

NO_DATA_RADIUS_PX = 50.0        # no observed corner nearer than this: no data (~8% of a 640 px width)
MAX_HALVES_DIFF_PX = 0.5        # two half-solutions further apart than this disagree
MAX_UNCERTAINTY_PX = 0.5


@dataclass
class RegionTrust:
    name: str
    untrusted_share: float          # of this ninth's grid points
    no_data_share: float
    max_halves_diff_px: float       # over the untrusted points (nan without cross-validation)
    max_uncertainty_px: float       # over the untrusted points (nan without uncertainty)

    def short(self) -> str:
        """What is wrong there, without the numbers behind it: "the top-left corner has no data"."""
        if self.no_data_share > 0:
            head = f"the {self.name} has no data"
            if self.no_data_share < 0.95:
                head += f" in {100 * self.no_data_share:.0f}% of it"
            return head
        return f"the {self.name} is not reliable"

    def sentence(self) -> str:
        parts = []
        head = self.short()
        if np.isfinite(self.max_halves_diff_px) and self.max_halves_diff_px > MAX_HALVES_DIFF_PX:
            parts.append(f"the halves disagree by {self.max_halves_diff_px:.1f} px there")
        elif np.isfinite(self.max_halves_diff_px):
            parts.append(f"the halves agree within {self.max_halves_diff_px:.2f} px there")
        if np.isfinite(self.max_uncertainty_px) and self.max_uncertainty_px > MAX_UNCERTAINTY_PX:
            parts.append(f"projection uncertainty {self.max_uncertainty_px:.1f} px")
        return head + (": " + ", ".join(parts) if parts else "")


@dataclass
class Validity:
    grid: np.ndarray                # (Ny, Nx, 2) pixels
    trusted: np.ndarray             # (Ny, Nx) bool
    nearest_corner_px: np.ndarray   # (Ny, Nx)
    halves_diff_px: np.ndarray | None
    uncertainty_px: np.ndarray | None
    region: np.ndarray              # (M, 2) closed polygon, pixels; (0, 2) when nothing is trusted
    regions: list[RegionTrust] = field(default_factory=list)   # ninths with untrusted points
    imagersize: tuple[int, int] | None = None   # None: the grid's extent (it covers the imager, border included)

    @property
    def trusted_share(self) -> float:
        return float(self.trusted.mean())

    @property
    def central_trusted_share(self) -> float:
        """Share of the grid points in the central 80% of the image (validate.central_mask) that are
        trusted; 0 when the grid has none there."""
        size = self.imagersize or (int(round(float(self.grid[..., 0].max()))) + 1,
                                   int(round(float(self.grid[..., 1].max()))) + 1)
        cm = central_mask(self.grid, size)
        return float(self.trusted[cm].mean()) if cm.any() else 0.0

    def summary(self) -> dict:
        return dict(trusted_share=self.trusted_share, central_trusted_share=self.central_trusted_share,
                    valid_intrinsics_region=[[float(x), float(y)] for x, y in self.region],
                    untrusted=[dict(region=r.name, share=r.untrusted_share, no_data_share=r.no_data_share,
                                    max_halves_diff_px=None if not np.isfinite(r.max_halves_diff_px)
                                    else r.max_halves_diff_px,
                                    max_uncertainty_px=None if not np.isfinite(r.max_uncertainty_px)
                                    else r.max_uncertainty_px, says=r.sentence()) for r in self.regions],
                    thresholds=dict(no_data_radius_px=NO_DATA_RADIUS_PX, max_halves_diff_px=MAX_HALVES_DIFF_PX,
                                    max_uncertainty_px=MAX_UNCERTAINTY_PX))


def _polygon(mask: np.ndarray, grid: np.ndarray) -> np.ndarray:
    """The outline of the largest connected trusted area, in pixels, closed (first = last)."""
    import cv2
    ny, nx = mask.shape
    contours = cv2.findContours(mask.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)[-2]
    if not contours:
        return np.zeros((0, 2))
    c = max(contours, key=lambda k: (cv2.contourArea(k), len(k)))[:, 0, :].astype(float)
    if len(c) < 3:
        return np.zeros((0, 2))
    x0, y0 = grid[0, 0]
    x1, y1 = grid[-1, -1]
    px = np.column_stack([x0 + c[:, 0] * (x1 - x0) / max(nx - 1, 1), y0 + c[:, 1] * (y1 - y0) / max(ny - 1, 1)])
    return np.vstack([px, px[:1]])


def validity(grid: np.ndarray, points: np.ndarray, imagersize: tuple[int, int], *,
             halves_diff_px: np.ndarray | None, uncertainty_px: np.ndarray | None) -> Validity:
    """``grid`` (Ny, Nx, 2); ``points`` (M, 2) inlier corners; the two maps on ``grid`` (or None)."""
    from scipy.spatial import cKDTree
    q = grid.reshape(-1, 2)
    if len(points):
        dist = cKDTree(points).query(q)[0].reshape(grid.shape[:2])
    else:
        dist = np.full(grid.shape[:2], np.inf)
    no_data = dist > NO_DATA_RADIUS_PX
    trusted = ~no_data
    if halves_diff_px is not None:
        trusted &= np.nan_to_num(halves_diff_px, nan=np.inf) <= MAX_HALVES_DIFF_PX
    if uncertainty_px is not None:
        trusted &= np.nan_to_num(uncertainty_px, nan=np.inf) <= MAX_UNCERTAINTY_PX
    w, h = imagersize
    col = np.clip((grid[..., 0] * 3 // w).astype(int), 0, 2)
    row = np.clip((grid[..., 1] * 3 // h).astype(int), 0, 2)
    regions = []
    for j in range(3):
        for i in range(3):
            cell = (row == j) & (col == i)
            bad = cell & ~trusted
            if not bad.any():
                continue
            hd = float(np.max(halves_diff_px[bad])) if halves_diff_px is not None else float("nan")
            un = float(np.max(uncertainty_px[bad])) if uncertainty_px is not None else float("nan")
            regions.append(RegionTrust(REGION_NAMES[j][i], float(bad.sum() / cell.sum()),
                                       float((cell & no_data).sum() / cell.sum()), hd, un))
    regions.sort(key=lambda r: -r.untrusted_share)
    return Validity(grid, trusted, dist, halves_diff_px, uncertainty_px, _polygon(trusted, grid), regions,
                    (int(w), int(h)))
