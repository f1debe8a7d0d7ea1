"""The second solver: OpenCV's fisheye calibration (Kannala-Brandt, cv2.fisheye.calibrate).

Seeded with the nominal focal length; CALIB_CHECK_COND is off (it rejects exactly the boards near
the image corners a fisheye needs). Outliers are handled like the mrcal solver: corners whose
residual is far outside the rest are dropped, then whole images that stand out, each named.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from calibration.lens import kannala_brandt as kb
from .mrcal_solver import (IMAGE_OUTLIER_FACTOR, IMAGE_OUTLIER_FLOOR_PX, MIN_CORNERS_PER_IMAGE,
                           MIN_IMAGES, RejectedImage, Solution, SolveError, _check_enough)
from .observations import BoardObservations

CORNER_OUTLIER_SIGMAS = 5.0    # a corner further than this many robust sigmas is an outlier
CORNER_OUTLIER_FLOOR_PX = 0.5
#: Kannala-Brandt terms that may be held at 0 (k4, then k3): a fit whose last terms fold inside the image
MAX_FIXED_TERMS = 2


def _fix_flags(fixed_terms: int) -> int:
    """cv2.fisheye flags holding Kannala-Brandt's last ``fixed_terms`` terms (0 to MAX_FIXED_TERMS) at 0."""
    import cv2
    if not 0 <= fixed_terms <= MAX_FIXED_TERMS:
        raise ValueError(f"fixed_terms {fixed_terms}: 0 to {MAX_FIXED_TERMS}")
    return (0, cv2.fisheye.CALIB_FIX_K4, cv2.fisheye.CALIB_FIX_K3 | cv2.fisheye.CALIB_FIX_K4)[fixed_terms]


def _calibrate(obs: BoardObservations, inlier: np.ndarray, focal_px: float, seed: np.ndarray | None = None,
               fixed_terms: int = 0):
    """(params (8,), residuals (N, H*W, 2) of every seen corner, poses (N, 6) Rodrigues r then t);
    ``seed``: params to start from (default: ``focal_px``, the centred principal point, no distortion);
    ``fixed_terms``: Kannala-Brandt's last terms held at 0 (1: k4; 2: k3 and k4), the others solved."""
    import cv2
    board_pts = obs.board_points_m()
    objp, imgp = [], []
    for i in range(obs.n):
        m = inlier[i]
        objp.append(board_pts[m].reshape(1, -1, 3).astype(np.float64))
        imgp.append(obs.corners[i, m].reshape(1, -1, 2).astype(np.float64))
    w, h = obs.imagersize
    K = np.array([[focal_px, 0, (w - 1) / 2], [0, focal_px, (h - 1) / 2], [0, 0, 1.0]])
    D = np.zeros((4, 1))
    if seed is not None:
        K = np.array([[seed[0], 0, seed[2]], [0, seed[1], seed[3]], [0, 0, 1.0]])
        D = np.asarray(seed[4:8], float).reshape(4, 1).copy()
    if fixed_terms:
        D[4 - fixed_terms:] = 0.0
    flags = cv2.fisheye.CALIB_RECOMPUTE_EXTRINSIC | cv2.fisheye.CALIB_FIX_SKEW | cv2.fisheye.CALIB_USE_INTRINSIC_GUESS \
        | _fix_flags(fixed_terms)
    crit = (cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, 200, 1e-12)
    try:
        _, K, D, rvecs, tvecs = cv2.fisheye.calibrate(objp, imgp, (w, h), K, D, flags=flags, criteria=crit)
    except cv2.error as exc:
        raise SolveError(f"cv2.fisheye.calibrate failed ({str(exc).strip().splitlines()[-1]}); "
                         f"try --solver mrcal") from None
    params = np.array([K[0, 0], K[1, 1], K[0, 2], K[1, 2], *np.ravel(D)])
    poses = np.array([np.concatenate([np.ravel(r), np.ravel(t)]) for r, t in zip(rvecs, tvecs)])
    # residuals of every seen corner (outliers included, so they can be judged)
    res = np.full(obs.corners.shape, np.nan)
    for i in range(obs.n):
        m = obs.seen()[i]
        R = cv2.Rodrigues(poses[i, :3])[0]
        pc = board_pts[m] @ R.T + poses[i, 3:]
        res[i, m] = obs.corners[i, m] - kb.project(pc, params)
    return params, res, poses


def _per_image(res: np.ndarray, inlier: np.ndarray):
    d2 = np.where(inlier, np.nansum(res ** 2, axis=-1), 0.0)
    per = np.sqrt(d2.sum(axis=1) / np.maximum(inlier.sum(axis=1), 1))
    return per, float(np.sqrt(d2.sum() / max(inlier.sum(), 1)))


def solve(obs: BoardObservations, *, focal_px: float, max_image_rejections: int = 3,
          fixed_terms: int = 0) -> Solution:
    """Kannala-Brandt solved by cv2.fisheye.calibrate from ``obs``, outlier corners and images rejected;
    ``fixed_terms``: its last terms held at 0 (1: k4; 2: k3 and k4; lens_choice.py tries them where
    the four-term fit folds inside the image)."""
    keep = obs.counts() >= MIN_CORNERS_PER_IMAGE
    rejected = [RejectedImage(nm, float("nan"), f"fewer than {MIN_CORNERS_PER_IMAGE} corners")
                for nm, k in zip(obs.names, keep) if not k]
    obs = obs.subset(keep)
    _check_enough(obs)
    inlier = obs.seen()
    for _round in range(max_image_rejections + 1):
        params, res, poses = _calibrate(obs, inlier, focal_px, fixed_terms=fixed_terms)
        mag = np.linalg.norm(res, axis=-1)
        sigma = 1.4826 * np.nanmedian(np.abs(mag[inlier])) if inlier.any() else 0.0
        outl = obs.seen() & (mag > max(CORNER_OUTLIER_SIGMAS * sigma, CORNER_OUTLIER_FLOOR_PX))
        new_inlier = obs.seen() & ~outl
        if (new_inlier != inlier).any():
            inlier = new_inlier
            params, res, poses = _calibrate(obs, inlier, focal_px, fixed_terms=fixed_terms)
        per, rms = _per_image(res, inlier)
        med = float(np.median(per))
        bad = (per > IMAGE_OUTLIER_FACTOR * med) & (per > IMAGE_OUTLIER_FLOOR_PX)
        if not bad.any() or obs.n - 1 < MIN_IMAGES or _round == max_image_rejections:
            break
        worst = int(np.argmax(np.where(bad, per, -1)))
        rejected.append(RejectedImage(obs.names[worst], float(per[worst]),
                                      f"RMS residual {per[worst]:.2f} px vs median {med:.2f} px "
                                      f"(a mis-detected or moving board)"))
        k = np.ones(obs.n, bool)
        k[worst] = False
        obs, inlier = obs.subset(k), inlier[k]
    w = obs.board[0]
    corners = [(obs.names[i], int(k % w), int(k // w), float(np.linalg.norm(res[i, k])))
               for i, k in zip(*np.nonzero(obs.seen() & ~inlier))]
    sol = Solution(kb.NAME, params, obs.imagersize, obs, {}, rms, per, res, inlier, rejected, corners,
                   solver="opencv", board_rt=poses, fixed_terms=fixed_terms)
    held = ("", "; k4 held at 0", "; k3 and k4 held at 0")[fixed_terms]
    sol.notes.append(f"OpenCV fisheye (Kannala-Brandt{held}); no projection uncertainty (mrcal computes that "
                     "from its own solve only)")
    return sol


def resolve(solution: Solution, obs: BoardObservations) -> Solution:
    """``solution`` solved again from ``obs`` (the same views, corners at other pixel positions: see
    mrcal_solver.resolve), from its own answer, with its inlier corners."""
    if list(obs.names) != list(solution.observations.names):
        raise SolveError("resolve: the observations are not the solution's views")
    params, res, poses = _calibrate(obs, solution.inlier, float(solution.intrinsics[0]),
                                    seed=np.asarray(solution.intrinsics, float), fixed_terms=solution.fixed_terms)
    per, rms = _per_image(res, solution.inlier)
    return dataclasses.replace(solution, intrinsics=params, observations=obs, rms_px=rms, per_image_rms_px=per,
                               residuals=res, board_rt=poses, rejected_images=list(solution.rejected_images),
                               rejected_corners=list(solution.rejected_corners), notes=list(solution.notes))
