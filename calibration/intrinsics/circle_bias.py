"""A circle grid's centroid bias, taken off in the solve (docs/calibration.md, "Circle grids").

The detector reports each disc's area centroid (calibration/detect/circles.py); the solver's model is
the projection of the disc's centre, and under perspective and a fisheye the two differ by
:func:`~calibration.detect.circles.disc_centroid_bias`, which depends on the lens and the board's pose:
what is being solved. So the correction is iterated (:func:`solve_corrected`):

    round 0: solve from the detected centroids
    round k: the bias of every seen disc from round k-1's lens and board poses; solve again from
             the detected centroids minus that bias

Stop rule: when the largest change of any disc's correction between two rounds is below
STOP_CHANGE_PX (a fiftieth of a good corner's noise, 0.05 px: further rounds cannot move the lens by
anything measurable), or after MAX_ROUNDS corrections. The bias is a smooth, slowly varying function
of the pose (0.5 px at most for a 41 px disc tilted 45 deg, bench/bench_circles.py), so the iteration
is a contraction: three or four rounds in practice (each round cut the change by 3-100x on the
sets measured; a poor first lens, OPENCV8 on the published Boson lens, took 0.3x per round).

Round 0 is the caller's (the default's model choice included); every later round is a warm re-solve
of the previous round's lens and board poses by the same solver (mrcal_solver.resolve,
opencv_solver.resolve) with round 0's settings and inlier decisions: re-running the whole solve
each round re-decided mrcal's outliers on the moving input, and the iteration cycled between two
lenses 0.16 px apart in fx (Kannala-Brandt truth, 14 steep views).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from calibration.detect.circles import disc_centroid_bias
from calibration.formats.conversions import lens_projector

from .mrcal_solver import Solution
from .observations import BoardObservations

MAX_ROUNDS = 10           # corrections after the first solve
STOP_CHANGE_PX = 1e-3     # the largest change of a disc's correction between rounds that still iterates


class CircleBiasError(ValueError):
    """A disc radius the board cannot have; ``str()`` names it."""


def check_radius(radius_m: float, spacing_m: float) -> float:
    """The disc radius (metres), refused unless 0 < r < spacing / 2 (discs on a lattice of ``spacing_m``
    would touch at half a spacing)."""
    if not np.isfinite(radius_m) or not 0 < radius_m < 0.5 * spacing_m:
        raise CircleBiasError(f"--circle-radius {radius_m:g}: expected the discs' radius in metres, more than 0 and "
                              f"less than half the spacing ({0.5 * spacing_m:g} m for --square {spacing_m:g})")
    return float(radius_m)


def projector(solution: Solution) -> Callable[[np.ndarray], np.ndarray]:
    """points (..., 3) in the camera frame -> pixels (..., 2) through ``solution``'s lens."""
    return lens_projector(solution.lensmodel, solution.intrinsics)


def board_poses(solution: Solution) -> np.ndarray:
    """(N, 6) rt_cam_board (Rodrigues r then t, metres) of every view of ``solution``."""
    oi = solution.optimization_inputs
    if oi:
        return np.array(oi["frames_rt_toref"][oi["indices_frame_camintrinsics_camextrinsics"][:, 0]], float)
    return np.asarray(solution.board_rt, float)


def centroid_bias(solution: Solution, radius_m: float) -> np.ndarray:
    """(N, H*W, 2) px: the centroid bias of every disc ``solution``'s views saw (NaN where not seen),
    from its lens and board poses."""
    import cv2
    obs = solution.observations
    project = projector(solution)
    pts = obs.board_points_m()
    out = np.full(obs.corners.shape, np.nan)
    seen = obs.seen()
    for i, rt in enumerate(board_poses(solution)):
        m = seen[i]
        if not m.any():
            continue
        R = cv2.Rodrigues(np.asarray(rt[:3], float))[0]
        out[i, m] = disc_centroid_bias(project, R, rt[3:], pts[m], radius_m)
    return out


def corrected(raw: BoardObservations, names: list[str], bias: np.ndarray) -> BoardObservations:
    """The views ``names`` of ``raw`` (detected centroids) with ``bias`` (len(names), H*W, 2) taken off."""
    index = {n: i for i, n in enumerate(raw.names)}
    sub = raw.subset([index[n] for n in names])
    b = np.where(np.isfinite(bias), bias, 0.0)
    return BoardObservations(sub.names, sub.corners - b, sub.weights, sub.board, sub.square_m, sub.imagersize,
                             sub.missed, sub.missed_why, sub.bit_depth)


@dataclass
class Rounds:
    """What the iteration did, for the report: per round the largest and RMS change of the correction,
    the RMS residual and the focal length; whether the stop rule was met."""
    radius_m: float
    rows: list[dict] = field(default_factory=list)
    converged: bool = False

    def summary(self) -> dict:
        last = self.rows[-1] if self.rows else {}
        return dict(radius_m=self.radius_m, rounds=len(self.rows) - 1, converged=self.converged,
                    stop_change_px=STOP_CHANGE_PX, max_rounds=MAX_ROUNDS,
                    bias_rms_px=last.get("bias_rms_px"), bias_max_px=last.get("bias_max_px"), per_round=self.rows)

    def note(self) -> str:
        s = self.summary()
        how = (f"stopped after {s['rounds']} round(s): the correction changed by less than {STOP_CHANGE_PX:g} px"
               if self.converged else f"not converged after {s['rounds']} rounds (largest change "
                                      f"{self.rows[-1]['max_change_px']:.3g} px)")
        return (f"circle centres: each disc's centroid bias (radius {1000 * self.radius_m:g} mm) taken off, "
                f"RMS {s['bias_rms_px']:.3f} px, largest {s['bias_max_px']:.3f} px; {how}")


def _row(k: int, sol: Solution, bias: np.ndarray | None, change: np.ndarray | None) -> dict:
    mag = None if bias is None else np.linalg.norm(bias, axis=-1)
    fin = None if mag is None else mag[np.isfinite(mag)]
    ch = None if change is None else change[np.isfinite(change)]
    return dict(round=k, rms_px=float(sol.rms_px), fx=float(sol.intrinsics[0]), fy=float(sol.intrinsics[1]),
                bias_rms_px=None if fin is None or not fin.size else float(np.sqrt(np.mean(fin ** 2))),
                bias_max_px=None if fin is None or not fin.size else float(fin.max()),
                max_change_px=None if ch is None or not ch.size else float(ch.max()))


def resolver(solution: Solution) -> Callable[[Solution, BoardObservations], Solution]:
    """The warm re-solve of ``solution``'s solver (mrcal_solver.resolve or opencv_solver.resolve)."""
    from . import mrcal_solver, opencv_solver
    return opencv_solver.resolve if solution.solver == "opencv" else mrcal_solver.resolve


def solve_corrected(raw: BoardObservations, first: Solution, radius_m: float, *, max_rounds: int = MAX_ROUNDS,
                    stop_change_px: float = STOP_CHANGE_PX) -> tuple[Solution, Rounds]:
    """``first`` (round 0: solved from the detected centroids, its views a subset of ``raw``'s) solved
    again with each disc's centroid bias taken off, until the stop rule (module docstring). Each round
    is a warm re-solve of the previous one's lens and poses with round 0's settings and inlier
    decisions (:func:`resolver`), so the rounds differ only by the correction."""
    again = resolver(first)
    names = list(first.observations.names)
    sol = first
    rounds = Rounds(radius_m, [_row(0, sol, None, None)])
    prev = np.zeros_like(first.observations.corners)
    for k in range(1, max_rounds + 1):
        bias = centroid_bias(sol, radius_m)
        change = np.linalg.norm(np.where(np.isfinite(bias), bias, 0.0) - prev, axis=-1)
        change[~sol.observations.seen()] = np.nan
        sol = again(sol, corrected(raw, names, bias))
        rounds.rows.append(_row(k, sol, bias, change))
        prev = np.where(np.isfinite(bias), bias, 0.0)
        ch = change[np.isfinite(change)]
        if ch.size and float(ch.max()) < stop_change_px:
            rounds.converged = True
            break
    sol.centroid_correction = rounds.summary()
    sol.notes.append(rounds.note())
    return sol, rounds
