"""The thermal pair's left-right pose from shared board views, with mrcal.

The reference frame is the left camera's optical frame (mrcal camera 0, identity extrinsics); the
right camera's ``extrinsics_rt_fromref`` is ``rt_right_left`` (maps left-camera points into the right
camera, metres). Seeds: both lenses from the mono models, the pose from CAD, each board's pose by PnP
through the left lens (mrcal.unproject, then cv2.solvePnP on the normalised rays).

Stages (mrcal.optimize, one lens model for both cameras as mrcal 2.2 requires):
1. lenses held, the pose and every board pose, no regularisation (with the lenses held there is
   nothing to regularise), mrcal's outlier rejection on;
2. ``refine_intrinsics``: both lenses, the pose, the boards and the board warp jointly, with mrcal's
   regularisation, from stage 1's solution.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from platform_tools.rig.frames import Pose

from calibration.intrinsics.quiet import quiet_stderr
from .pairs import StereoObservations

MIN_SHARED_VIEWS = 5       # fewer board poses seen by both cameras do not pin a 6-DOF pose and check it


class StereoSolveError(Exception):
    """The views cannot be solved; ``str()`` says why and what to do."""


@dataclass
class StereoSolution:
    models: tuple                    # (left, right) mrcal.cameramodel, left = reference, with optimization_inputs
    rt_right_left: np.ndarray        # (6,) mrcal rt, metres
    rms_px: tuple[float, float]      # per camera, over inlier corners
    n_views: int
    n_outliers: int
    refined_intrinsics: bool
    optimization_inputs: dict | None = None   # the solved mrcal problem (centroids.py re-solves it warm)

    @property
    def T_left_right(self) -> Pose:
        """The right optical frame in the left one (mm)."""
        return Pose.from_rt(self.rt_right_left, metres=True).inverse()


def board_pose_pnp(q: np.ndarray, lensmodel: str, intrinsics: np.ndarray, points_m: np.ndarray) -> np.ndarray:
    """rt_cam_board (6,) (metres) of a board seen at pixels ``q`` (M, 2) (NaN where not seen) whose
    corners are ``points_m`` (M, 3): PnP on the rays mrcal unprojects. Raises StereoSolveError."""
    import cv2
    import mrcal
    ok = np.isfinite(q[:, 0])
    if ok.sum() < 6:
        raise StereoSolveError(f"only {int(ok.sum())} corners: cannot place the board")
    v = mrcal.unproject(np.ascontiguousarray(q[ok]), lensmodel, intrinsics)
    xy = v[:, :2] / v[:, 2:3]
    good, rvec, tvec = cv2.solvePnP(points_m[ok], xy, np.eye(3), None, flags=cv2.SOLVEPNP_ITERATIVE)
    if not good:
        raise StereoSolveError("PnP failed: cannot place the board")
    return np.concatenate([rvec.ravel(), tvec.ravel()])


def observations_board(obs: StereoObservations) -> np.ndarray:
    """mrcal observations_board (2N, H, W, 3): view k's left then right image, weight -1 where unseen."""
    W, H = obs.board
    rows = []
    for k in range(obs.n):
        for q, w in ((obs.left[k], obs.weights_left[k]), (obs.right[k], obs.weights_right[k])):
            o = np.empty((H, W, 3))
            seen = np.isfinite(q[:, 0]) & (w > 0)
            o[..., :2] = np.where(seen[:, None], q, -1.0).reshape(H, W, 2)
            o[..., 2] = np.where(seen, w, -1.0).reshape(H, W)
            rows.append(o)
    return np.array(rows)


def optimization_inputs(obs: StereoObservations, lenses, rt_right_left: np.ndarray) -> dict:
    """mrcal optimization_inputs of the pair with the lenses held (stage 1), seeded as the module says."""
    lm = lenses[0].intrinsics()[0]
    intr = np.array([m.intrinsics()[1] for m in lenses], float)
    pts = obs.board_points_m()
    frames = np.array([board_pose_pnp(obs.left[k], lm, intr[0], pts) for k in range(obs.n)])
    idx = np.array([(k, c, c - 1) for k in range(obs.n) for c in (0, 1)], np.int32)
    return dict(intrinsics=intr, extrinsics_rt_fromref=np.asarray(rt_right_left, float).reshape(1, 6).copy(),
                frames_rt_toref=frames, points=None, observations_board=observations_board(obs),
                indices_frame_camintrinsics_camextrinsics=idx, observations_point=None,
                indices_point_camintrinsics_camextrinsics=None, lensmodel=lm,
                imagersizes=np.array([m.imagersize() for m in lenses], np.int32), calobject_warp=np.zeros(2),
                do_optimize_intrinsics_core=False, do_optimize_intrinsics_distortions=False,
                do_optimize_extrinsics=True, do_optimize_frames=True, do_optimize_calobject_warp=False,
                calibration_object_spacing=obs.square_m, do_apply_outlier_rejection=True,
                do_apply_regularization=False, verbose=False)


def residuals_px(oi: dict) -> np.ndarray:
    """(2N, H*W, 2) observed minus predicted pixels of every observation row of ``oi``, NaN where the
    corner is not seen or was rejected as an outlier (weight <= 0)."""
    import mrcal
    obs = oi["observations_board"]
    n, H, W, _ = obs.shape
    j, i = np.mgrid[0:H, 0:W]
    s = oi["calibration_object_spacing"]
    pts = mrcal.ref_calibration_object(W, H, s, calobject_warp=oi["calobject_warp"]).reshape(-1, 3)
    out = np.full((n, H * W, 2), np.nan)
    for r, (f, ci, ce) in enumerate(oi["indices_frame_camintrinsics_camextrinsics"]):
        p = mrcal.transform_point_rt(oi["frames_rt_toref"][f], pts)
        if ce >= 0:
            p = mrcal.transform_point_rt(oi["extrinsics_rt_fromref"][ce], p)
        q = mrcal.project(p, oi["lensmodel"], oi["intrinsics"][ci])
        o = obs[r].reshape(-1, 3)
        seen = o[:, 2] > 0
        out[r, seen] = o[seen, :2] - q[seen]
    return out


def solve_pair(obs: StereoObservations, lenses, rt_right_left_seed: np.ndarray, *, refine_intrinsics: bool = False,
               min_views: int = MIN_SHARED_VIEWS, verbose: bool = False) -> StereoSolution:
    """Solve the pair from the views both cameras saw. ``lenses``: (left, right) mrcal.cameramodel with the
    same lens model and imager size as their images; ``rt_right_left_seed`` (6,) the seed pose (metres).
    Raises StereoSolveError when fewer than ``min_views`` views are shared."""
    import mrcal
    if lenses[0].intrinsics()[0] != lenses[1].intrinsics()[0]:
        raise StereoSolveError(f"the models are {lenses[0].intrinsics()[0]} and {lenses[1].intrinsics()[0]}: "
                               f"mrcal solves one lens model for both cameras")
    keep = obs.shared()
    if keep.sum() < min_views:
        raise StereoSolveError(f"{int(keep.sum())} of {obs.n} board poses seen by both cameras (at least "
                               f"{min_views} needed); take more views with the whole board in both images")
    obs = obs.subset(keep)
    oi = optimization_inputs(obs, lenses, rt_right_left_seed)
    weighed = int(np.sum(oi["observations_board"][..., 2] > 0))
    with quiet_stderr(not verbose):
        mrcal.optimize(**oi)
        if refine_intrinsics:
            oi.update(do_optimize_intrinsics_core=True, do_optimize_intrinsics_distortions=True,
                      do_optimize_calobject_warp=True, do_apply_regularization=True)
            mrcal.optimize(**oi)
    # mrcal marks an outlier by its weight (<= 0) in observations_board, and its Noutliers counts every
    # such point, the unseen ones too (an asymmetric grid's absent half, a partial view's missing
    # corners): the outliers are the points seen and weighed before the solve, not after it
    outliers = weighed - int(np.sum(oi["observations_board"][..., 2] > 0))
    return solution(oi, obs.n, outliers, refine_intrinsics)


def solution(oi: dict, n_views: int, n_outliers: int, refined_intrinsics: bool) -> StereoSolution:
    """The StereoSolution of the solved mrcal problem ``oi``."""
    import mrcal
    r = residuals_px(oi)
    rms = tuple(float(np.sqrt(np.nanmean(np.sum(r[c::2] ** 2, axis=-1)))) for c in (0, 1))
    models = tuple(mrcal.cameramodel(optimization_inputs=oi, icam_intrinsics=c) for c in (0, 1))
    return StereoSolution(models, np.array(oi["extrinsics_rt_fromref"][0], float), rms, n_views, n_outliers,
                          refined_intrinsics, oi)


def pose_difference(T_seed: Pose, T: Pose) -> dict:
    """How far pose ``T`` is from ``T_seed`` (both the right optical frame in the left one, mm):
    baselines (mm), the translation difference (mm, left frame) and the rotation between them (deg)."""
    D = T_seed.inverse() @ T
    return {"baseline_mm": float(np.linalg.norm(T.t)), "seed_baseline_mm": float(np.linalg.norm(T_seed.t)),
            "translation_mm": float(np.linalg.norm(T.t - T_seed.t)), "rotation_deg": float(D.angle_deg()),
            "xyz_mm": [float(x) for x in T.t], "seed_xyz_mm": [float(x) for x in T_seed.t]}
