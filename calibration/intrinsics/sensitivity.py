"""How corner errors move a camera model: the first-order change of a solved mrcal problem's
parameters caused by given errors in its observed corners.

At the optimum of the least-squares problem min |x(p)|^2, a small change dq of the observed corners
moves the solution by dp = -(J^T J)^-1 J^T dx, where dx is how the measurements change (mrcal's board
measurements are x = w (q_predicted - q_observed), so dx = -w dq). Used on synthetic data, where the
problem sits at the true lens and board poses (x = 0), this says what a detector's errors alone do
to the intrinsics: zero-mean noise spreads solutions around the truth, and a systematic error (a
shift that depends on where a corner lies or how its board is posed) biases them, which no number of
images removes. Nothing is re-solved, so mrcal's outlier rejection cannot hide a bias by luck (in a
full solve it can: see docs/calibration-synthetic.md, "What biases the intrinsics").
"""
from __future__ import annotations

import numpy as np


def problem_at_truth(lensmodel: str, intrinsics: np.ndarray, rt_cam_board: np.ndarray, corners: np.ndarray,
                     board: tuple[int, int], square_m: float, imagersize: tuple[int, int], *,
                     optimize_warp: bool = True) -> dict:
    """mrcal optimisation inputs for one camera at the truth: ``rt_cam_board`` (N, 6) board poses,
    ``corners`` (N, H*W, 2) the observed corners' TRUE positions (NaN where not observed: those are
    left out, as a detector that missed them would leave them out). Unregularised and without outlier
    rejection, as the final OPENCV8 solve of calibrate thermal; the board warp is a free parameter as
    there (``optimize_warp``)."""
    import mrcal

    from .mrcal_solver import _base_inputs
    from .observations import BoardObservations
    n = len(rt_cam_board)
    c = np.asarray(corners, float).reshape(n, -1, 2)
    obs = BoardObservations([str(i) for i in range(n)], c, np.ones(c.shape[:2]), tuple(board), float(square_m),
                            tuple(imagersize))
    oi = _base_inputs(obs, lensmodel, intrinsics, rt_cam_board)
    oi.update(do_apply_regularization=False, do_optimize_extrinsics=False,
              calobject_warp=np.zeros(2) if optimize_warp else None,
              do_optimize_calobject_warp=optimize_warp)
    mrcal.optimize(**oi)      # already at the optimum up to float rounding; this only polishes
    return oi


def parameter_shift(optimization_inputs: dict, corner_errors: np.ndarray) -> dict:
    """First-order change of the solution when every observed corner moves by ``corner_errors``
    (N, H*W, 2) pixels (NaN or 0 where not observed). Returns the unpacked shifts: ``intrinsics``
    (the first camera's), ``frames_rt_toref`` (N, 6) and ``calobject_warp`` (2,) when optimised."""
    import mrcal
    import scipy.sparse.linalg as sla
    oi = optimization_inputs
    if not (oi["do_optimize_intrinsics_core"] and oi["do_optimize_intrinsics_distortions"]
            and oi["do_optimize_frames"]) or oi["do_optimize_extrinsics"]:
        raise ValueError("parameter_shift expects one camera with its intrinsics and board poses optimised "
                         "(as problem_at_truth sets up)")
    ob = oi["observations_board"]
    n, h, w, _ = ob.shape
    _, x, J = mrcal.optimizer_callback(**oi)[:3]
    J = J.tocsc()
    e = np.nan_to_num(np.asarray(corner_errors, float).reshape(n, h, w, 2))
    wt = np.where(ob[..., 2] > 0, ob[..., 2], 0.0)
    dx = np.zeros(len(x))
    dx[:n * h * w * 2] = (-wt[..., None] * e).ravel()
    JtJ = (J.T @ J).tocsc()
    dp = -sla.splu(JtJ).solve(J.T @ dx)
    mrcal.unpack_state(dp, **oi)
    nint = oi["intrinsics"].shape[-1]
    out = {"intrinsics": dp[:nint].copy(), "frames_rt_toref": dp[nint:nint + 6 * n].reshape(n, 6).copy()}
    if oi.get("do_optimize_calobject_warp") and oi.get("calobject_warp") is not None:
        out["calobject_warp"] = dp[nint + 6 * n:nint + 6 * n + 2].copy()
    return out


def projection_shift(lensmodel: str, intrinsics: np.ndarray, d_intrinsics: np.ndarray,
                     imagersize: tuple[int, int], *, grid_width: int = 64) -> tuple[np.ndarray, np.ndarray]:
    """First-order projection difference (pixels) over the imager when ``intrinsics`` move by
    ``d_intrinsics``, after the best-fit rotation (as calibration.lens.compare and mrcal's projection_diff
    compare two lenses). Linear like :func:`parameter_shift`: a near-degenerate direction of the lens
    model (OPENCV8's rational terms growing together) moves its parameters a lot and its projection
    little, and evaluating the moved model exactly would mix a second-order effect into a first-order
    answer. Returns (grid (Ny, Nx, 2), difference (Ny, Nx); NaN where the unprojection failed)."""
    import mrcal

    from calibration.lens.fit import imager_grid
    grid = imager_grid(imagersize, grid_width)
    q = grid.reshape(-1, 2)
    v = mrcal.unproject(np.ascontiguousarray(q), lensmodel, np.asarray(intrinsics, float), normalize=True)
    ok = np.isfinite(v).all(axis=1)
    # mrcal's numerical unprojection of a rational model misses at the odd pixel: leave those out
    ok[ok] = np.linalg.norm(mrcal.project(np.ascontiguousarray(v[ok]), lensmodel, np.asarray(intrinsics, float))
                            - q[ok], axis=1) < 1e-3
    _, dq_dv, dq_di = mrcal.project(np.ascontiguousarray(v[ok]), lensmodel, np.asarray(intrinsics, float),
                                    get_gradients=True)
    dq = dq_di @ np.asarray(d_intrinsics, float)                  # (M, 2)
    # a rotation w moves each ray by w x v = -[v]x w: dq_rot = dq_dv @ (-[v]x) w
    vx = np.zeros((len(v[ok]), 3, 3))
    a, b, c = v[ok].T
    vx[:, 0, 1], vx[:, 0, 2], vx[:, 1, 2] = -c, b, -a
    vx[:, 1, 0], vx[:, 2, 0], vx[:, 2, 1] = c, -b, a
    A = -np.einsum("mij,mjk->mik", dq_dv, vx).reshape(-1, 3)
    w = np.linalg.lstsq(A, -dq.reshape(-1), rcond=None)[0]
    d = np.full(len(q), np.nan)
    d[ok] = np.linalg.norm(dq + (A @ w).reshape(-1, 2), axis=1)
    return grid, d.reshape(grid.shape[:2])
