"""The joint solve: thermal intrinsics and every camera's extrinsics with mrcal, seeded from CAD.

mrcal.optimize with the four cameras at once (mrcal 2.2 takes one lens model for all cameras:
LENSMODEL_OPENCV8; the ZED's pinhole seed is OPENCV8 with zero distortion, exactly the same lens).
The reference frame is the ZED X left optical frame, whose pose in the rig is taken from CAD: the
data says where the cameras are relative to each other, never where the rig's origin is, and the
ZED is what every other sensor of the rig is referred to.

Stages:
1. intrinsics held at their seeds (ZED: nominal or given models; thermal: the nominal Boson lens),
   extrinsics seeded from CAD, board poses from PnP in one camera: extrinsics and boards only;
2. everything jointly: all intrinsics, extrinsics, board poses, board warp, with outlier rejection
   and mrcal's regularisation;
3. ``zed_intrinsics="fixed"`` (the default): the ZED intrinsics are put back to their given models
   and extrinsics and boards are solved again with every lens held (mrcal 2.2 cannot hold the lens of
   some cameras and free others in one solve); ``"solved"`` keeps stage 2's ZED lens.
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from platform_tools.rig.cameras import camera_model, imagersize
from platform_tools.rig.frames import Pose

from calibration.intrinsics.quiet import quiet_stderr
from .cad import CAMERAS, FrameTree
from .sets import RigObservations

LENSMODEL = "LENSMODEL_OPENCV8"
ORDER = tuple(CAMERAS)            # icam: 0 zed_left (the reference), 1 zed_right, 2 thermal_left, 3 thermal_right


class RigSolveError(Exception):
    pass


@dataclass
class RigSolution:
    T_ref_cam: dict[str, Pose]            # refined: camera optical frame in the ZED left optical frame (mm)
    lenses: dict                       # camera short name -> solved mrcal.cameramodel (OPENCV8)
    inputs: dict                          # mrcal optimization_inputs of the final solve
    rms_px: dict[str, float]              # per camera, inliers
    n_obs: dict[str, int]
    n_outliers: int


def as_opencv8(lens) -> np.ndarray:
    """The OPENCV8 intrinsics (12,) of ``lens`` (an mrcal.cameramodel of a pinhole or OPENCV4/5/8 lens)."""
    lensmodel, p = lens.intrinsics()
    p = np.asarray(p, dtype=float)
    if lensmodel == LENSMODEL:
        return p.copy()
    if lensmodel in ("LENSMODEL_PINHOLE", "LENSMODEL_OPENCV4", "LENSMODEL_OPENCV5"):
        out = np.zeros(12)
        out[:len(p)] = p
        return out
    raise RigSolveError(f"cannot seed {lensmodel} as {LENSMODEL}; give an OPENCV4/5/8 or pinhole model")


def _pnp(q: np.ndarray, lens: tuple[str, np.ndarray], obj_m: np.ndarray) -> Pose | None:
    import mrcal
    ok = np.isfinite(q[:, 0])
    if ok.sum() < 6:
        return None
    v = mrcal.unproject(np.ascontiguousarray(q[ok]), lens[0], lens[1])
    xy = v[:, :2] / v[:, 2:3]
    good, rvec, tvec = cv2.solvePnP(obj_m[ok], xy, np.eye(3), None, flags=cv2.SOLVEPNP_ITERATIVE)
    if not good:
        return None
    return Pose.from_rt(np.concatenate([rvec.ravel(), tvec.ravel()]), metres=True)


def _inputs(obs: RigObservations, intrinsics: np.ndarray, ext: np.ndarray, frames: np.ndarray) -> dict:
    W, H = obs.board
    rows, idx = [], []
    for i in range(obs.n):
        for k, c in enumerate(ORDER):
            if not obs.seen(c)[i]:
                continue
            o = np.empty((H, W, 3))
            q = obs.corners[c][i]
            ok = np.isfinite(q[:, 0])
            o[..., :2] = np.where(ok[:, None], q, -1.0).reshape(H, W, 2)
            o[..., 2] = np.where(ok, obs.weights[c][i], -1.0).reshape(H, W)
            rows.append(o)
            idx.append((i, k, k - 1))
    return dict(intrinsics=intrinsics, extrinsics_rt_fromref=ext, frames_rt_toref=frames, points=None,
                observations_board=np.array(rows), indices_frame_camintrinsics_camextrinsics=np.array(idx, np.int32),
                observations_point=None, indices_point_camintrinsics_camextrinsics=None, lensmodel=LENSMODEL,
                imagersizes=np.array([obs.imagersizes[c] for c in ORDER], np.int32), calobject_warp=np.zeros(2),
                do_optimize_intrinsics_core=False, do_optimize_intrinsics_distortions=False,
                do_optimize_extrinsics=True, do_optimize_frames=True, do_optimize_calobject_warp=False,
                calibration_object_spacing=obs.square_m, do_apply_outlier_rejection=False,
                do_apply_regularization=True, verbose=False)


def _seed_frames(obs: RigObservations, intrinsics: np.ndarray, T_ref_cam: dict[str, Pose]) -> np.ndarray:
    W, H = obs.board
    j, i = np.mgrid[0:H, 0:W]
    obj = np.stack([i.ravel() * obs.square_m, j.ravel() * obs.square_m, np.zeros(W * H)], axis=1)
    frames = np.zeros((obs.n, 6))
    for n in range(obs.n):
        best = max(ORDER, key=lambda c: np.isfinite(obs.corners[c][n][:, 0]).sum())
        T = _pnp(obs.corners[best][n], (LENSMODEL, intrinsics[ORDER.index(best)]), obj)
        if T is None:
            raise RigSolveError(f"set {obs.sets[n].key}: cannot estimate the board pose from {best}")
        frames[n] = (T_ref_cam[best] @ T).rt(metres=True)
    return frames


def prior_residuals(oi: dict, prior: dict, T_ref_cad: dict[str, Pose], scale: float) -> np.ndarray:
    """The extrinsics prior's residuals: per camera with a prior, ``scale * L^-1 xi`` where ``xi`` is the
    camera's pose against CAD relative to the reference camera (the twist of ``T_cad^-1 T``, mm and
    rad, optical axes) and ``L L^T`` the prior's covariance; ``scale`` puts them in pixels (the
    measurements' noise), so a camera one sigma from CAD costs what one pixel of noise costs."""
    out = []
    for c, cov in prior.items():
        k = ORDER.index(c) - 1
        T = Pose.from_rt(oi["extrinsics_rt_fromref"][k], metres=True).inverse()
        D = T_ref_cad[c].inverse() @ T
        xi = np.concatenate([D.t, D.rt()[:3]])
        # a floor of 1e-12 (mm^2, rad^2) keeps a rig with zero tolerances on some axis solvable (a stiff prior)
        out.append(scale * np.linalg.solve(np.linalg.cholesky(cov + 1e-12 * np.eye(6)), xi))
    return np.concatenate(out) if out else np.zeros(0)


def optimize_holding(oi: dict, hold: list[int], iterations: int = 30, prior: dict | None = None,
                     T_ref_cad: dict[str, Pose] | None = None) -> None:
    """Minimise mrcal's own cost (its residuals and regularisation, as ``mrcal.optimizer_callback``
    gives them) over every state mrcal would optimise except the intrinsics of the cameras ``hold``:
    Levenberg-Marquardt on mrcal's Jacobian with those columns removed. mrcal 2.2 can only hold every
    camera's lens or none; this is the joint solve with the ZED's lens held. Outlier weights stay as
    the previous mrcal.optimize left them. ``prior`` (camera -> 6x6 covariance, mm and rad, optical
    axes; :func:`prior_residuals`) adds the CAD stack-up's prior on those cameras' extrinsics (about
    ``T_ref_cad``), its Jacobian by central differences on the six packed states of each. Updates
    ``oi`` in place."""
    import mrcal
    import scipy.sparse as sp
    n_cam = oi["intrinsics"].shape[0]
    per = mrcal.num_states_intrinsics(**oi) // n_cam
    keys = ("intrinsics", "extrinsics_rt_fromref", "frames_rt_toref", "calobject_warp")
    prior = prior or {}
    if prior:   # the measurements' noise (px) that the prior's residuals are scaled by
        x0 = mrcal.optimizer_callback(**oi, no_factorization=True, no_jacobian=True)[1]
        scale = float(np.sqrt(np.mean(x0 ** 2)))

    def evaluate():
        b, x, J, _ = mrcal.optimizer_callback(**oi, no_factorization=True)
        if not prior:
            return b, x, J
        r = prior_residuals(oi, prior, T_ref_cad, scale)
        Jp = np.zeros((len(r), len(b)))
        saved = np.array(oi["extrinsics_rt_fromref"], copy=True)
        for c in prior:
            i0 = mrcal.state_index_extrinsics(ORDER.index(c) - 1, **oi)
            for j in range(i0, i0 + 6):
                cols = []
                for h in (1e-6, -1e-6):
                    bb = b.copy()
                    bb[j] += h
                    mrcal.ingest_packed_state(bb, **oi)
                    cols.append(prior_residuals(oi, prior, T_ref_cad, scale))
                    oi["extrinsics_rt_fromref"][...] = saved
                Jp[:, j] = (cols[0] - cols[1]) / 2e-6
        mrcal.ingest_packed_state(b, **oi)
        return b, np.concatenate([x, r]), sp.vstack([J, sp.csr_matrix(Jp)]).tocsr()

    b, x, J = evaluate()
    cols = np.ones(J.shape[1], bool)
    for k in hold:
        i0 = mrcal.state_index_intrinsics(k, **oi)
        cols[i0:i0 + per] = False
    cost = float(x @ x)
    lam = 1e-6
    for _ in range(iterations):
        Jk = J[:, np.flatnonzero(cols)]
        JtJ = (Jk.T @ Jk).toarray()
        g = Jk.T @ x
        saved = {k: np.array(oi[k], copy=True) for k in keys if oi.get(k) is not None}
        improved = False
        for _ in range(8):
            A = JtJ + lam * np.diag(np.maximum(np.diag(JtJ), 1e-12))
            step = np.zeros(J.shape[1])
            step[cols] = -np.linalg.solve(A, g)
            mrcal.ingest_packed_state(b + step, **oi)
            b2, x2, J2 = evaluate()
            c2 = float(x2 @ x2)
            if c2 < cost:
                improved = True
                break
            for k, v in saved.items():
                oi[k][...] = v
            lam *= 10
        if not improved:
            break
        rel = (cost - c2) / max(cost, 1e-300)
        b, x, J, cost = b2, x2, J2, c2
        lam = max(lam / 10, 1e-9)
        if rel < 1e-10:
            break


def _rms(oi: dict, obs_cams: np.ndarray) -> tuple[dict[str, float], int]:
    import mrcal
    x = mrcal.optimizer_callback(**oi)[1]
    nb = oi["observations_board"].shape[0] * oi["observations_board"].shape[1] * oi["observations_board"].shape[2]
    r = x[:nb * 2].reshape(-1, 2)
    w = oi["observations_board"][..., 2].ravel()
    r = r / np.where(w > 0, w, 1.0)[:, None]        # residuals are weighted; back to pixels
    cams = np.repeat(obs_cams, oi["observations_board"].shape[1] * oi["observations_board"].shape[2])
    out = {}
    for k, c in enumerate(ORDER):
        m = (cams == k) & (w > 0)
        out[c] = float(np.sqrt(np.mean(np.sum(r[m] ** 2, axis=1)))) if m.any() else float("nan")
    return out, int(np.sum(w <= 0))


def solve_rig(obs: RigObservations, seeds: dict, cad: FrameTree, *,
              zed_intrinsics: str = "fixed", prior: dict | None = None) -> RigSolution:
    """The joint solve; ``prior``: camera short name -> 6x6 covariance (mm, rad; optical axes) of its pose
    relative to the ZED left camera about CAD (calibration/extrinsics/prior.py), applied in the last stage."""
    with quiet_stderr():
        return _solve_rig(obs, seeds, cad, zed_intrinsics, prior)


def _solve_rig(obs: RigObservations, seeds: dict, cad: FrameTree,
               zed_intrinsics: str, prior: dict | None = None) -> RigSolution:
    import mrcal
    if zed_intrinsics not in ("fixed", "solved"):
        raise ValueError(zed_intrinsics)
    intr = np.array([as_opencv8(seeds[c]) for c in ORDER])
    ref = CAMERAS["zed_left"]
    T_ref_cam = {c: cad.T(ref, CAMERAS[c]) for c in ORDER}
    ext = np.array([T_ref_cam[c].inverse().rt(metres=True) for c in ORDER[1:]])
    frames = _seed_frames(obs, intr, T_ref_cam)
    oi = _inputs(obs, intr, ext, frames)
    mrcal.optimize(**oi)                                                    # 1
    oi.update(do_optimize_intrinsics_core=True, do_optimize_intrinsics_distortions=True,
              do_optimize_calobject_warp=True, do_apply_outlier_rejection=True)
    mrcal.optimize(**oi)                                                    # 2
    if zed_intrinsics == "fixed":                                           # 3
        for c in ("zed_left", "zed_right"):
            oi["intrinsics"][ORDER.index(c)] = as_opencv8(seeds[c])
        oi.update(do_optimize_intrinsics_core=False, do_optimize_intrinsics_distortions=False,
                  do_apply_outlier_rejection=False)
        mrcal.optimize(**oi)                  # extrinsics and boards under the given ZED lens
        oi.update(do_optimize_intrinsics_core=True, do_optimize_intrinsics_distortions=True)
        optimize_holding(oi, [ORDER.index("zed_left"), ORDER.index("zed_right")], prior=prior, T_ref_cad=T_ref_cam)
    elif prior:
        optimize_holding(oi, [], prior=prior, T_ref_cad=T_ref_cam)
    if not np.all(np.isfinite(oi["extrinsics_rt_fromref"])):
        raise RigSolveError("the joint solve diverged")
    cams = oi["indices_frame_camintrinsics_camextrinsics"][:, 1]
    rms, n_out = _rms(oi, cams)
    T = {"zed_left": Pose.identity()}
    for k, c in enumerate(ORDER[1:]):
        T[c] = Pose.from_rt(oi["extrinsics_rt_fromref"][k], metres=True).inverse()
    lenses = {c: camera_model(LENSMODEL, oi["intrinsics"][k].copy(), tuple(obs.imagersizes[c]))
              for k, c in enumerate(ORDER)}
    n_obs = {c: int(np.sum(cams == k)) for k, c in enumerate(ORDER)}
    return RigSolution(T, lenses, oi, rms, n_obs, n_out)


def refined_tree(cad: FrameTree, sol: RigSolution) -> FrameTree:
    """The rig's frames with the refined cameras: the ZED left optical frame stays at its CAD pose
    (the anchor), every other camera is placed relative to it; body frames follow their optical frames."""
    from platform_tools.rig.frames import T_BODY_OPTICAL
    T = dict(cad.T_rig)
    anchor = cad.T_rig[CAMERAS["zed_left"]]
    for c, frame in CAMERAS.items():
        T[frame] = anchor @ sol.T_ref_cam[c]
        body = frame.removesuffix("_optical")
        if body in T:
            T[body] = T[frame] @ T_BODY_OPTICAL.inverse()
    return FrameTree(T, dict(cad.parent), cad.rig_hash)


def difference(a: Pose, b: Pose) -> tuple[float, float, Pose]:
    """(mm, deg, D) with D = a^-1 b: b seen from a (a camera's refined pose against its CAD pose)."""
    D = a.inverse() @ b
    return float(np.linalg.norm(D.t)), D.angle_deg(), D


def rgb_to_thermal_px(zed, thermal, T_th_zed: Pose, depth_m: float,
                      grid: tuple[int, int] = (24, 15)) -> np.ndarray:
    """Where points at ``depth_m`` (along the ZED left's optical axis) seen on a grid of ZED left pixels
    land in the thermal image, through ``T_th_zed`` (mm); ``zed``, ``thermal``: mrcal.cameramodel (their lenses);
    (N, 2) px, NaN outside the thermal image."""
    import mrcal
    W, H = imagersize(zed)
    xs, ys = np.meshgrid(np.linspace(0.05, 0.95, grid[0]) * (W - 1), np.linspace(0.05, 0.95, grid[1]) * (H - 1))
    q = np.stack([xs.ravel(), ys.ravel()], axis=1)
    v = mrcal.unproject(np.ascontiguousarray(q), *zed.intrinsics())
    p = v / v[:, 2:3] * depth_m * 1000.0
    pt = T_th_zed.apply(p) / 1000.0
    out = mrcal.project(np.ascontiguousarray(pt), *thermal.intrinsics())
    Wt, Ht = imagersize(thermal)
    ok = (pt[:, 2] > 0) & (out[:, 0] >= 0) & (out[:, 0] <= Wt - 1) & (out[:, 1] >= 0) & (out[:, 1] <= Ht - 1)
    out[~ok] = np.nan
    return out


def mapping_error_px(ref: np.ndarray, other: np.ndarray) -> dict[str, float]:
    d = np.linalg.norm(other - ref, axis=1)
    d = d[np.isfinite(d)]
    return {"rms_px": float(np.sqrt(np.mean(d ** 2))) if d.size else float("nan"),
            "max_px": float(d.max()) if d.size else float("nan"), "points": int(d.size)}
