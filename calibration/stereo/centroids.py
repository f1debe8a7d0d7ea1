"""A circle grid's centroid bias taken off in the pair's solve, as the mono solve takes it off
(calibration/intrinsics/circle_bias.py, whose stop rule and round limit this uses).

Each camera's detector reports every disc's area centroid, which is not the projection of the
disc's centre (calibration/detect/circles.disc_centroid_bias): the bias depends on the lens and on
the board's pose in that camera, so the left and the right image of one board pose carry different
biases, and a pose solved from the raw centroids absorbs their difference. Round 0 is the pair
solved from the detected centroids (solve.solve_pair); each later round computes every seen disc's
bias in both cameras from the previous round's lenses, board poses and left-right pose (the right
camera's board pose is rt_right_left composed with the left's) and re-solves the same mrcal problem
warm from the centroids minus it: the previous round's poses (and lenses, with
--refine-intrinsics) as the seed, round 0's inlier decisions kept, no new outlier rejection (a
re-decided inlier set on a moving input cycles, as the mono solve found). The bias is computed for
every detected disc, the ones round 0 set aside as outliers too (on raw centroids mrcal's rejection
takes out the most biased discs: 22 of 696 on a rendered set of 8 steep pairs): they stay out of the
solve, but the epipolar error is measured on every disc, and a raw one there reads as pose error.
"""
from __future__ import annotations

import copy

import numpy as np

from calibration.detect.circles import disc_centroid_bias
from calibration.formats.conversions import lens_projector
from calibration.intrinsics.circle_bias import MAX_ROUNDS, STOP_CHANGE_PX
from calibration.intrinsics.quiet import quiet_stderr

from .pairs import StereoObservations
from .solve import StereoSolution, observations_board, solution


def detected(obs: StereoObservations) -> np.ndarray:
    """(2N, H*W) bool: the discs each camera's detector found, in the solve's row order (view k's
    left row 2k, right row 2k + 1)."""
    return np.stack([np.isfinite(obs.left[..., 0]), np.isfinite(obs.right[..., 0])], axis=1).reshape(
        2 * obs.n, -1)


def pair_bias(oi: dict, points_m: np.ndarray, radius_m: float, seen: np.ndarray | None = None) -> np.ndarray:
    """(2N, H*W, 2) px: the centroid bias of every disc each observation row of the solved problem
    ``oi`` saw (view k's left row 2k, right row 2k + 1), from its lenses and poses; NaN where unseen.
    ``points_m`` (H*W, 3): the disc centres on the board. ``seen`` (2N, H*W) bool: the discs to
    compute it for (default: those the solve weighs; pass detected() so that the discs mrcal's
    outlier rejection set aside are corrected too: the epipolar error is measured on every disc)."""
    import cv2
    import mrcal
    obs = oi["observations_board"]
    n, H, W, _ = obs.shape
    out = np.full((n, H * W, 2), np.nan)
    for r, (f, ci, ce) in enumerate(oi["indices_frame_camintrinsics_camextrinsics"]):
        seen_r = obs[r].reshape(-1, 3)[:, 2] > 0 if seen is None else np.asarray(seen[r], bool)
        if not seen_r.any():
            continue
        rt = np.asarray(oi["frames_rt_toref"][f], float)
        if ce >= 0:
            rt = mrcal.compose_rt(np.asarray(oi["extrinsics_rt_fromref"][ce], float), rt)
        R = cv2.Rodrigues(rt[:3])[0]
        project = lens_projector(oi["lensmodel"], oi["intrinsics"][ci])
        out[r, seen_r] = disc_centroid_bias(project, R, rt[3:], points_m[seen_r], radius_m)
    return out


def corrected(obs: StereoObservations, bias: np.ndarray) -> StereoObservations:
    """``obs`` (detected centroids, the rows of ``bias``) with ``bias`` (2N, H*W, 2) taken off."""
    b = np.where(np.isfinite(bias), bias, 0.0)
    return StereoObservations(list(obs.names), obs.left - b[0::2], obs.right - b[1::2], obs.weights_left,
                              obs.weights_right, obs.board, obs.square_m)


def solve_pair_corrected(obs: StereoObservations, first: StereoSolution, radius_m: float, *,
                         max_rounds: int = MAX_ROUNDS, stop_change_px: float = STOP_CHANGE_PX,
                         verbose: bool = False) -> tuple[StereoSolution, StereoObservations, dict]:
    """``first`` (solve.solve_pair on ``obs``'s shared views: round 0) solved again with each disc's
    centroid bias taken off in both cameras, until the largest change of any disc's correction
    between two rounds is below ``stop_change_px`` or after ``max_rounds``. Returns the solution, the
    shared views' centre estimates (centroids minus the last bias: what the epipolar error is
    measured on) and the rounds (per round: largest change, the bias's RMS and largest, the
    baseline and the RMS residuals)."""
    import mrcal
    shared = obs.subset(obs.shared())
    raw = observations_board(shared)
    pts = shared.board_points_m()
    oi = first.optimization_inputs
    sol, cent = first, shared
    rows = [_row(0, first, None, None)]
    prev = np.zeros(raw.shape[:1] + (raw.shape[1] * raw.shape[2], 2))
    converged = False
    seen = detected(shared)
    for k in range(1, max_rounds + 1):
        bias = pair_bias(oi, pts, radius_m, seen)
        b = np.where(np.isfinite(bias), bias, 0.0)
        change = np.linalg.norm(b - prev, axis=-1)[np.isfinite(bias[..., 0])]
        oi = copy.deepcopy(oi)
        ob = oi["observations_board"]            # weights as round 0 left them (its outliers stay out)
        ob[..., :2] = raw[..., :2] - b.reshape(ob.shape[:3] + (2,))
        oi["do_apply_outlier_rejection"] = False
        with quiet_stderr(not verbose):
            mrcal.optimize(**oi)
        sol = solution(oi, first.n_views, first.n_outliers, first.refined_intrinsics)
        cent = corrected(shared, bias)
        rows.append(_row(k, sol, bias, change))
        prev = b
        if change.size and float(change.max()) < stop_change_px:
            converged = True
            break
    last = rows[-1]
    summary = dict(radius_m=float(radius_m), rounds=len(rows) - 1, converged=converged,
                   stop_change_px=stop_change_px, max_rounds=max_rounds, bias_rms_px=last["bias_rms_px"],
                   bias_max_px=last["bias_max_px"], per_round=rows)
    return sol, cent, summary


def _row(k: int, sol: StereoSolution, bias, change) -> dict:
    mag = None if bias is None else np.linalg.norm(bias, axis=-1)
    fin = None if mag is None else mag[np.isfinite(mag)]
    return dict(round=k, rms_px_left=float(sol.rms_px[0]), rms_px_right=float(sol.rms_px[1]),
                baseline_mm=float(1000 * np.linalg.norm(sol.rt_right_left[3:])),
                bias_rms_px=None if fin is None or not fin.size else float(np.sqrt(np.mean(fin ** 2))),
                bias_max_px=None if fin is None or not fin.size else float(fin.max()),
                max_change_px=None if change is None or not change.size else float(change.max()))
