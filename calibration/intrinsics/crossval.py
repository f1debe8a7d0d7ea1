"""Cross-validation, as mrcal recommends: solve again on two disjoint halves of the images and see
where across the image the two solutions disagree.

Projection uncertainty is a linearisation at the data and says nothing about a model that goes
wrong where no board was seen; reprojection error says even less. Two halves of the data that each
pin the lens down agree to within their noise; where the lens is defined only by extrapolation (or
by regularisation) they drift apart. The disagreement map, with the coverage map and the
uncertainty, is what the verdict and the valid-intrinsics region are made of (report/validity.py).

The halves are disjoint and balanced: images are ordered by the direction from the image centre to
their board's centroid and dealt alternately, so each half sees boards on every side when the set
does. Each half is solved from the full solution's intrinsics and board poses with the same lens
model, the same inlier corners and the same regularisation, so the two differ only by their data.
The rotation between the two halves' cameras is fitted over the central half of the image (a
rotation is not a lens difference; as mrcal's projection_diff fits it in a focus region).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from calibration.lens import kannala_brandt as kb
from calibration.lens.fit import robust_unproject
from .mrcal_solver import MIN_IMAGES, Solution

GRID_WIDTH = 32          # the validity grid: 32 x 26 points over a 640 x 512 imager, border included
FIT_FRACTION = 0.5       # the rotation between the halves is fitted over the central half


class CrossValidationError(Exception):
    """A half could not be solved or compared on this data (a real-data failure, not a bug to show as a
    traceback); ``str()`` says which half and what failed, in one line."""


@dataclass(frozen=True)
class CrossValidation:
    grid: np.ndarray             # (Ny, Nx, 2) pixels
    diff_px: np.ndarray          # (Ny, Nx) projection difference between the two halves' solutions
    halves: tuple[list[str], list[str]]
    rms_px: float
    max_px: float

    def summary(self) -> dict:
        return dict(rms_px=self.rms_px, max_px=self.max_px, n_images=[len(h) for h in self.halves])


def split(solution: Solution) -> tuple[np.ndarray, np.ndarray]:
    """Two disjoint index arrays covering the images, balanced by where the boards are."""
    obs = solution.observations
    w, h = obs.imagersize
    c = np.array([np.nanmean(obs.corners[i][solution.inlier[i]], axis=0) if solution.inlier[i].any()
                  else [w / 2, h / 2] for i in range(obs.n)])
    ang = np.arctan2(c[:, 1] - (h - 1) / 2, c[:, 0] - (w - 1) / 2)
    order = np.argsort(ang, kind="stable")
    return np.sort(order[0::2]), np.sort(order[1::2])


def _mrcal_half(solution: Solution, idx: np.ndarray):
    import mrcal
    oi = solution.optimization_inputs
    half = {k: (np.array(v, copy=True) if isinstance(v, np.ndarray) else v) for k, v in oi.items()}
    half["observations_board"] = np.array(oi["observations_board"][idx], copy=True)
    half["frames_rt_toref"] = np.array(oi["frames_rt_toref"][idx], copy=True)
    n = len(idx)
    half["indices_frame_camintrinsics_camextrinsics"] = \
        np.column_stack([np.arange(n), np.zeros(n), -np.ones(n)]).astype(np.int32)
    half["do_apply_outlier_rejection"] = False      # the full solve's inlier decisions stand
    mrcal.optimize(**half)
    lm, intr = half["lensmodel"], half["intrinsics"][0]
    return (lambda v: mrcal.project(np.ascontiguousarray(v), lm, intr),
            lambda q: robust_unproject(q, lm, intr))


def _opencv_half(solution: Solution, idx: np.ndarray):
    from .opencv_solver import _calibrate
    obs = solution.observations.subset(idx)
    p = np.asarray(solution.intrinsics, dtype=float)
    params, _, _ = _calibrate(obs, solution.inlier[idx], float(p[0]), fixed_terms=solution.fixed_terms)
    return (lambda v: kb.project(v, params)), (lambda q: kb.unproject(q, params))


def solve_subset(solution: Solution, idx: np.ndarray):
    """(project, unproject) of ``solution``'s lens solved again from the views ``idx`` only, from its
    own answer, with its inlier corners (also used by model_choice.py for held-out views)."""
    return (_opencv_half if solution.solver == "opencv" else _mrcal_half)(solution, idx)


def cross_validate(solution: Solution, *, grid_width: int = GRID_WIDTH) -> CrossValidation | None:
    """The halves' disagreement across the image; None when a half would have fewer than
    mrcal_solver.MIN_IMAGES images (too few to solve: the caller says so)."""
    from calibration.lens.compare import compare
    a, b = split(solution)
    if min(len(a), len(b)) < MIN_IMAGES:
        return None
    half = solve_subset
    stage = "the first half's solve"
    try:
        proj_a, unproj_a = half(solution, a)
        stage = "the second half's solve"
        proj_b, _ = half(solution, b)
        stage = "comparing the two halves"
        c = compare(proj_b, unproj_a, solution.imagersize, grid_width=grid_width, fit_fraction=FIT_FRACTION)
    except Exception as exc:      # noqa: BLE001 - mrcal, OpenCV and scipy raise plain errors on real data
        detail = " ".join(str(exc).split())[:160] or type(exc).__name__
        raise CrossValidationError(f"{stage} ({len(a)} and {len(b)} images) failed: {detail}") from None
    names = solution.observations.names
    d = np.where(np.isfinite(c.diff_px), c.diff_px, np.inf)
    fin = d[np.isfinite(d)]
    return CrossValidation(c.grid, d, ([names[i] for i in a], [names[i] for i in b]),
                           float(np.sqrt(np.mean(fin ** 2))) if fin.size else float("inf"), float(d.max()))
