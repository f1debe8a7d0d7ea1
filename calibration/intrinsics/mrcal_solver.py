"""Solve a single camera's intrinsics with mrcal, in-process, with outliers rejected and named.

The sequence follows mrcal's own calibration tool: a stereographic seed from the nominal focal length
(board poses by PnP), geometry-only then core-only presolves, then the full model. Differences:

- OPENCV8 starts from the presolved stereographic lens expressed as OPENCV8 (a linear fit of its
  radial profile, calibration/lens/radial.py), not from zero distortion, so a 95 deg lens starts close
  to where it ends, and the same data always starts from the same seed.
- A splined model first gets an OPENCV8-free stereographic core, which is then fixed (as mrcal's
  tool does: the core is redundant with the spline), and the knots' fov_x covers the measured field.
- Board poses are re-estimated by PnP through the model solved so far, while that helps.
- After mrcal's per-corner outlier rejection, whole images whose residuals stand out from the rest
  (a mis-detected or moved board) are removed by name, and the problem is solved again.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from calibration.lens import health
from calibration.lens.fit import fit_lensmodel, mrcal_unprojector
from calibration.lens.radial import opencv8_from_stereographic

from . import lensmodels
from .observations import BoardObservations


class SolveError(Exception):
    """The data cannot be solved (too few boards or corners); ``str()`` says what to do."""


MIN_IMAGES = 4            # fewer boards than this cannot pin down a fisheye's intrinsics
MIN_CORNERS_PER_IMAGE = 8  # a board pose has 6 unknowns; fewer corners than this is not a board
# An image is an outlier when its RMS residual exceeds both this multiple of the median image's
# and this absolute floor (pixels): at 0.05-0.3 px corner noise a good board never gets there.
IMAGE_OUTLIER_FACTOR = 4.0
IMAGE_OUTLIER_FLOOR_PX = 0.5
# ... or when mrcal's corner outlier rejection threw out more than this share of its corners
IMAGE_OUTLIER_CORNER_SHARE = 0.3


@dataclass
class RejectedImage:
    name: str
    rms_px: float
    reason: str


@dataclass
class Solution:
    lensmodel: str
    intrinsics: np.ndarray
    imagersize: tuple[int, int]
    observations: BoardObservations      # the images used in the final solve
    optimization_inputs: dict
    rms_px: float                        # RMS reprojection error over inlier corners
    per_image_rms_px: np.ndarray         # (N,) over inlier corners
    residuals: np.ndarray                # (N, H*W, 2) observed - predicted, NaN where not seen
    inlier: np.ndarray                   # (N, H*W) bool: seen and not rejected
    rejected_images: list[RejectedImage] = field(default_factory=list)
    rejected_corners: list[tuple[str, int, int, float]] = field(default_factory=list)  # name, col, row, |res|
    solver: str = "mrcal"                # mrcal | opencv (cv2.fisheye)
    notes: list[str] = field(default_factory=list)
    board_rt: np.ndarray | None = None   # (N, 6) board poses of a solver without optimization_inputs
    model_choice: dict | None = None     # how the default model was chosen (model_choice.Choice.summary)
    centroid_correction: dict | None = None  # circle grids: the bias iteration (circle_bias.Rounds.summary)
    fixed_terms: int = 0                 # opencv (Kannala-Brandt): its last terms held at 0 (1: k4; 2: k3, k4)

    def cameramodel(self, note: str | None = None):
        import mrcal
        kw = dict(optimization_inputs=self.optimization_inputs, icam_intrinsics=0) \
            if self.optimization_inputs else \
            dict(intrinsics=(self.lensmodel, self.intrinsics), imagersize=self.imagersize)
        return mrcal.cameramodel(**kw)


def _indices(n: int) -> np.ndarray:
    return np.column_stack([np.arange(n), np.zeros(n), -np.ones(n)]).astype(np.int32)


def _check_enough(obs: BoardObservations) -> None:
    counts = obs.counts()
    good = int((counts >= MIN_CORNERS_PER_IMAGE).sum())
    if good < MIN_IMAGES:
        raise SolveError(f"only {good} image(s) with at least {MIN_CORNERS_PER_IMAGE} detected corners "
                         f"({obs.n} with any, {len(obs.missed)} without a board); at least {MIN_IMAGES} are "
                         f"needed: take more images with the board filling different parts of the image")


def predicted(optimization_inputs: dict) -> np.ndarray:
    """(N, H, W, 2) where the solved model puts every board corner."""
    import mrcal
    oi = optimization_inputs
    obs = oi["observations_board"]
    _, h, w, _ = obs.shape
    obj = mrcal.ref_calibration_object(w, h, oi["calibration_object_spacing"],
                                       calobject_warp=oi.get("calobject_warp"))
    frames = oi["frames_rt_toref"][oi["indices_frame_camintrinsics_camextrinsics"][:, 0]]
    pcam = mrcal.transform_point_rt(frames[:, None, None, :], obj[None])
    return mrcal.project(pcam, oi["lensmodel"], oi["intrinsics"][0])


def residual_summary(obs: BoardObservations, optimization_inputs: dict):
    """residuals (N, H*W, 2), inlier mask (N, H*W), per-image RMS (N,), overall RMS."""
    q = predicted(optimization_inputs).reshape(obs.n, -1, 2)
    res = obs.corners - q
    inlier = obs.seen() & (optimization_inputs["observations_board"][..., 2].reshape(obs.n, -1) > 0)
    d2 = np.where(inlier, (res ** 2).sum(axis=-1), 0.0)
    cnt = np.maximum(inlier.sum(axis=1), 1)
    per_image = np.sqrt(d2.sum(axis=1) / cnt)
    rms = float(np.sqrt(d2.sum() / max(inlier.sum(), 1)))
    return np.where(obs.seen()[..., None], res, np.nan), inlier, per_image, rms


def _seed(obs: BoardObservations, focal_px: float):
    import mrcal
    observations = obs.mrcal_array()
    idx = np.column_stack([np.arange(obs.n), np.zeros(obs.n)]).astype(np.int32)
    imagersizes = np.array([obs.imagersize], dtype=np.int32)
    intrinsics, _, frames = mrcal.seed_stereographic(imagersizes=imagersizes, focal_estimate=focal_px,
                                                     indices_frame_camera=idx, observations=observations,
                                                     object_spacing=obs.square_m)
    return intrinsics, frames


def _base_inputs(obs: BoardObservations, lensmodel: str, intrinsics: np.ndarray, frames: np.ndarray) -> dict:
    return dict(intrinsics=np.atleast_2d(np.asarray(intrinsics, dtype=float)).copy(),
                extrinsics_rt_fromref=np.zeros((0, 6)), frames_rt_toref=np.asarray(frames, dtype=float).copy(),
                points=None, observations_board=obs.mrcal_array(),
                indices_frame_camintrinsics_camextrinsics=_indices(obs.n),
                observations_point=None, indices_point_camintrinsics_camextrinsics=None,
                lensmodel=lensmodel, imagersizes=np.array([obs.imagersize], dtype=np.int32),
                calobject_warp=None, do_optimize_intrinsics_core=True,
                do_optimize_intrinsics_distortions=True, do_optimize_extrinsics=True,
                do_optimize_frames=True, do_optimize_calobject_warp=False,
                calibration_object_spacing=obs.square_m, do_apply_outlier_rejection=False,
                do_apply_regularization=True, verbose=False)


def _stereographic_presolve(obs: BoardObservations, focal_px: float) -> dict:
    import mrcal
    intrinsics, frames = _seed(obs, focal_px)
    oi = _base_inputs(obs, "LENSMODEL_STEREOGRAPHIC", intrinsics, frames)
    oi.update(do_optimize_intrinsics_core=False, do_optimize_intrinsics_distortions=False,
              do_apply_regularization=False)
    mrcal.optimize(**oi)
    oi.update(do_optimize_intrinsics_core=True)
    mrcal.optimize(**oi)
    return oi


def horizontal_fov_deg(lensmodel: str, intrinsics: np.ndarray, imagersize: tuple[int, int]) -> float:
    """The angle between the rays of the left and right edges of the imager, through the centre row."""
    import mrcal
    w, h = imagersize
    cy = float(intrinsics[3])
    v = mrcal.unproject(np.array([[0.0, cy], [w - 1.0, cy]]), lensmodel, intrinsics, normalize=True)
    return math.degrees(math.atan2(abs(v[0, 0]), v[0, 2]) + math.atan2(abs(v[1, 0]), v[1, 2]))


def splined_fov_deg(lensmodel: str, intrinsics: np.ndarray, imagersize: tuple[int, int], nx: int, ny: int) -> float:
    """The smallest fov_x_deg whose knot grid (Nx x Ny, equal spacing in stereographic u = 2 tan(theta/2))
    covers every pixel of the imager's border through the given lens, plus one knot spacing."""
    import mrcal
    w, h = imagersize
    t = np.linspace(0, 1, 41)
    border = np.concatenate([np.column_stack([t * (w - 1), np.zeros_like(t)]),
                             np.column_stack([t * (w - 1), np.full_like(t, h - 1)]),
                             np.column_stack([np.zeros_like(t), t * (h - 1)]),
                             np.column_stack([np.full_like(t, w - 1), t * (h - 1)])])
    v = mrcal.unproject(border, lensmodel, intrinsics, normalize=True)
    th = np.arctan2(np.hypot(v[:, 0], v[:, 1]), v[:, 2])
    u = 2 * np.tan(th / 2)[:, None] * v[:, :2] / np.maximum(np.hypot(v[:, 0], v[:, 1]), 1e-12)[:, None]
    ux = max(float(np.abs(u[:, 0]).max()), float(np.abs(u[:, 1]).max()) * (nx - 1) / (ny - 1))
    ux *= (nx - 1) / (nx - 3)          # one spare knot spacing on each side
    return math.degrees(4 * math.atan(ux / 2))


def _expand(pre: dict, lensmodel: str, imagersize: tuple[int, int]) -> tuple[np.ndarray, bool]:
    """Intrinsics of ``lensmodel`` seeded from the stereographic presolve; and whether to optimise
    the core."""
    import mrcal
    core = pre["intrinsics"][0]
    n = mrcal.lensmodel_num_params(lensmodel)
    if lensmodels.is_splined(lensmodel):
        # a splined stereographic with zero spline values is exactly this stereographic lens
        x = np.zeros(n)
        x[:4] = core
        return x, False
    if lensmodel == "LENSMODEL_OPENCV8":
        # linear and exact for one input: an iterative pixel fit ended anywhere in the rational terms'
        # valley of near-equal fits, so the same data solved differently after other work in the process
        return opencv8_from_stereographic(core, imagersize), True
    fit = fit_lensmodel(mrcal_unprojector("LENSMODEL_STEREOGRAPHIC", core), imagersize, lensmodel, core)
    return fit.intrinsics, True


def _rms(oi: dict) -> float:
    import mrcal
    return float(mrcal.optimize(**oi)["rms_reproj_error__pixels"])


def _board_errors(obs: BoardObservations, lensmodel: str, intrinsics: np.ndarray, i: int, rt: np.ndarray) -> float:
    import mrcal
    m = obs.seen()[i]
    p = mrcal.transform_point_rt(rt, obs.board_points_m()[m])
    q = mrcal.project(p, lensmodel, intrinsics)
    return float(np.sqrt(np.mean(np.sum((q - obs.corners[i, m]) ** 2, axis=-1))))


def _fix_poses(obs: BoardObservations, oi: dict, *, factor: float = 2.0) -> list[int]:
    """A small or distant board has two poses that look alike (tilted towards or away from the
    camera: the planar pose ambiguity), and a stereographic seed often picks the wrong one; mrcal
    cannot leave that minimum, and the board then looks like an outlier (8 px RMS on the bench set,
    3 of 39 images thrown away). For every board, both IPPE solutions through the model solved so far
    are tried (rays unprojected by the model, so the lens's distortion is out of the way); a pose
    that fits the board ``factor`` times better replaces the current one. Returns the boards changed."""
    import cv2
    import mrcal
    lm, intr = oi["lensmodel"], oi["intrinsics"][0]
    objp = obs.board_points_m()
    frames = oi["frames_rt_toref"]
    changed = []
    for i in range(obs.n):
        m = obs.seen()[i]
        if m.sum() < 4:
            continue
        v = mrcal.unproject(np.ascontiguousarray(obs.corners[i, m]), lm, intr)
        if not np.all(np.isfinite(v)) or np.any(v[:, 2] <= 1e-6):
            continue
        xy = np.ascontiguousarray(v[:, :2] / v[:, 2:3])
        cur = _board_errors(obs, lm, intr, i, frames[i])
        best, best_err = None, cur
        try:
            _, rvecs, tvecs, _ = cv2.solvePnPGeneric(objp[m], xy, np.eye(3), None, flags=cv2.SOLVEPNP_IPPE)
        except cv2.error:
            continue
        for r, t in zip(rvecs, tvecs):
            r, t = cv2.solvePnPRefineLM(objp[m], xy, np.eye(3), None, r.copy(), t.copy())
            rt = np.concatenate([np.ravel(r), np.ravel(t)])
            err = _board_errors(obs, lm, intr, i, rt)
            if np.isfinite(err) and err < best_err:
                best, best_err = rt, err
        if best is not None and best_err * factor < cur:
            frames[i] = best
            changed.append(i)
    return changed


def _repose(obs: BoardObservations, oi: dict, rounds: int = 3) -> list[int]:
    """Re-solve while :func:`_fix_poses` finds boards in the wrong one of their two poses."""
    import mrcal
    fixed: list[int] = []
    for _ in range(rounds):
        changed = _fix_poses(obs, oi)
        if not changed:
            break
        fixed += changed
        mrcal.optimize(**oi)
    return sorted(set(fixed))


# The unregularised polish is kept only when it stays sane: no distortion term runs off along the
# rational model's numerator/denominator degeneracy, and the fit is no worse than the regularised one.
UNREGULARISED_MAX_COEFF = 1e3


def _unregularised(oi: dict) -> tuple[dict, str]:
    """mrcal's regularisation pulls every distortion term towards zero. An OPENCV8 fit of a 95 deg
    lens needs terms of 3-7, so the pull bends the model where data is thin: on the bench set the
    extreme image corners came out 13 px off (0.67 px RMS over the image) with regularisation, 0.26 px
    worst (0.03 px RMS) without. So after the regularised solve (which converges reliably), the
    model is polished without it, keeping mrcal's outlier decisions. Splined models keep it: their
    knots where no board was seen are defined only by it. Returns the inputs to use and a note."""
    import mrcal
    if lensmodels.is_splined(oi["lensmodel"]) or not oi.get("do_apply_regularization", False):
        return oi, ""
    rms0 = _rms_of(oi)
    trial = {k: (np.array(v, copy=True) if isinstance(v, np.ndarray) else v) for k, v in oi.items()}
    trial.update(do_apply_regularization=False, do_apply_outlier_rejection=False)
    try:
        stats = mrcal.optimize(**trial)
        rms = float(stats["rms_reproj_error__pixels"])
    except Exception as exc:       # noqa: BLE001 - mrcal raises plain errors on a singular problem
        return oi, f"unregularised polish failed ({type(exc).__name__}); regularised model kept"
    d = trial["intrinsics"][0][4:]
    if not (np.all(np.isfinite(trial["intrinsics"])) and np.all(np.abs(d) < UNREGULARISED_MAX_COEFF)
            and rms <= 1.05 * rms0 + 1e-6):
        return oi, (f"unregularised polish rejected (RMS {rms:.3f} vs {rms0:.3f} px, largest term "
                    f"{np.max(np.abs(d)):.3g}); regularised model kept: it may be biased where data is thin")
    polished = health.check_mrcal(trial["lensmodel"], trial["intrinsics"][0], tuple(trial["imagersizes"][0]))
    if not polished.ok:
        kept = health.check_mrcal(oi["lensmodel"], oi["intrinsics"][0], tuple(oi["imagersizes"][0]))
        if kept.ok:
            return oi, (f"unregularised polish rejected: {polished.problem()}; regularised model kept: it may be "
                        f"biased where data is thin")
    note = "final solve without mrcal's regularisation (it biases a 95 deg OPENCV8 fit where data is thin)"
    if not _uncertainty_defined(trial):
        # the unregularised problem is singular (the rational terms' near-degeneracy): mrcal cannot
        # propagate noise through it. Keep the polished lens, but record the problem with mrcal's
        # regularisation on, as a weak prior that makes the uncertainty defined (a tiny cost at the
        # polished solution, whose effect on the uncertainty is second-order)
        trial["do_apply_regularization"] = True
        note += ("; the unregularised problem is singular, so the uncertainty is computed with the "
                 "regularisation as a prior")
    return trial, note


def _uncertainty_defined(oi: dict) -> bool:
    import mrcal
    try:
        m = mrcal.cameramodel(optimization_inputs=oi, icam_intrinsics=0)
        w, h = m.imagersize()
        v = mrcal.unproject(np.array([(w - 1) / 2, (h - 1) / 2]), *m.intrinsics(), normalize=True)
        s = mrcal.projection_uncertainty(v, model=m, atinfinity=True, what="worstdirection-stdev")
        return bool(np.all(np.isfinite(s)))
    except Exception:      # noqa: BLE001
        return False


def _rms_of(oi: dict) -> float:
    """RMS pixel residual of the corners mrcal counts as inliers (weight > 0)."""
    ob = oi["observations_board"]
    use = ob[..., 2] > 0
    d2 = np.sum((ob[..., :2] - predicted(oi)) ** 2, axis=-1)
    return float(np.sqrt(np.mean(d2[use]))) if use.any() else float("nan")


def _final(oi: dict) -> dict:
    """The full solve: outlier rejection and board warp on, mrcal's regularisation on. (Without
    regularisation an OPENCV8 fit of a 95 deg lens can run off along its rational degeneracy,
    numerator and denominator growing together to 1e5, and its JtJ is then singular, so no
    uncertainty; with it the fit is slightly biased: measured in bench/bench_intrinsics.py.)"""
    import mrcal
    # outliers are judged only now: against a half-converged model, the corners at the image's
    # edges (where a fisheye is hardest) look like outliers and would be thrown away
    oi.update(do_apply_outlier_rejection=True, calobject_warp=np.zeros(2), do_optimize_calobject_warp=True)
    mrcal.optimize(**oi)
    return oi


def solve(obs: BoardObservations, *, lensmodel: str | None, focal_px: float,
          max_image_rejections: int = 3) -> Solution:
    """Calibrate one camera. ``lensmodel``: a name :func:`lensmodels.resolve` accepts or None for the
    default; ``focal_px``: the nominal focal length, the seed."""
    import mrcal
    keep = obs.counts() >= MIN_CORNERS_PER_IMAGE
    rejected: list[RejectedImage] = [RejectedImage(nm, float("nan"), f"fewer than {MIN_CORNERS_PER_IMAGE} corners")
                                     for nm, k in zip(obs.names, keep) if not k]
    obs = obs.subset(keep)
    _check_enough(obs)

    pre = _stereographic_presolve(obs, focal_px)
    if not np.all(np.isfinite(pre["intrinsics"])) or pre["intrinsics"][0, 0] <= 0:
        raise SolveError("the stereographic presolve diverged: check --board and --square")
    fov = horizontal_fov_deg("LENSMODEL_STEREOGRAPHIC", pre["intrinsics"][0], obs.imagersize)
    full_name = lensmodels.resolve(lensmodel, obs.imagersize, fov * 1.05)
    notes: list[str] = []
    if lensmodels.is_splined(full_name):
        # a stereographic presolve underestimates a 95 deg lens's field (79 deg on the bench set), and
        # the spline's knots must cover the whole imager, corners included: measure the field
        # through an OPENCV8 solve, whose board poses also seed the spline
        o8 = _base_inputs(obs, "LENSMODEL_OPENCV8", _expand(pre, "LENSMODEL_OPENCV8", obs.imagersize)[0],
                          pre["frames_rt_toref"])
        mrcal.optimize(**o8)
        _repose(obs, o8)
        meta = mrcal.lensmodel_metadata_and_config(full_name)
        fov_x = splined_fov_deg("LENSMODEL_OPENCV8", o8["intrinsics"][0], obs.imagersize, meta["Nx"], meta["Ny"])
        if lensmodel is not None and lensmodel.strip().lower() in lensmodels.SHORT_NAMES:
            full_name = lensmodels.splined_name(obs.imagersize, fov_x, meta["Nx"])
        pre["frames_rt_toref"] = o8["frames_rt_toref"]

    for _round in range(max_image_rejections + 1):
        intr, opt_core = _expand(pre, full_name, obs.imagersize)
        oi = _base_inputs(obs, full_name, intr, pre["frames_rt_toref"])
        oi["do_optimize_intrinsics_core"] = opt_core
        mrcal.optimize(**oi)     # a first pass without outlier rejection from the fitted seed
        fixed = _repose(obs, oi)
        if fixed:
            notes.append(f"board pose ambiguity resolved (IPPE) for {', '.join(obs.names[i] for i in fixed)}")
        _final(oi)
        oi, note = _unregularised(oi)
        res, inlier, per_image, rms = residual_summary(obs, oi)
        med = float(np.median(per_image))
        share = 1.0 - inlier.sum(axis=1) / np.maximum(obs.seen().sum(axis=1), 1)
        bad = ((per_image > IMAGE_OUTLIER_FACTOR * med) & (per_image > IMAGE_OUTLIER_FLOOR_PX)) | \
            (share > IMAGE_OUTLIER_CORNER_SHARE)
        if not bad.any() or obs.n - bad.sum() < MIN_IMAGES or _round == max_image_rejections:
            break
        # one at a time: one bad board inflates the others' residuals
        worst = int(np.argmax(np.where(bad, per_image / max(med, 1e-9) + 10 * share, -1)))
        rms_all = float(np.sqrt(np.nanmean(np.sum(res[worst] ** 2, axis=-1))))
        rejected.append(RejectedImage(obs.names[worst], rms_all,
                                      f"{100 * share[worst]:.0f}% of its corners are outliers, RMS residual "
                                      f"{rms_all:.2f} px vs median image {med:.2f} px (a mis-detected or "
                                      f"moving board)"))
        keep = np.ones(obs.n, bool)
        keep[worst] = False
        obs = obs.subset(keep)
        pre["frames_rt_toref"] = oi["frames_rt_toref"][keep]
        pre["observations_board"] = obs.mrcal_array()

    rejected_corners = []
    outl = obs.seen() & ~inlier
    w = obs.board[0]
    for i, k in zip(*np.nonzero(outl)):
        rejected_corners.append((obs.names[i], int(k % w), int(k // w), float(np.linalg.norm(res[i, k]))))
    if note:
        notes.append(note)
    return Solution(full_name, oi["intrinsics"][0].copy(), obs.imagersize, obs, oi, rms, per_image, res,
                    inlier, rejected, rejected_corners, notes=notes)


def resolve(solution: Solution, obs: BoardObservations) -> Solution:
    """``solution`` solved again from ``obs``: the same views and corners at other pixel positions (a
    circle grid's centres with their centroid bias taken off, calibration/intrinsics/circle_bias.py),
    from its own answer and with its own settings and inlier decisions (mrcal's outliers stay out, no
    new rejection: re-deciding them on a moving input flips corners in and out and an iteration
    then cycles)."""
    import mrcal
    if list(obs.names) != list(solution.observations.names):
        raise SolveError("resolve: the observations are not the solution's views")
    oi = {k: (np.array(v, copy=True) if isinstance(v, np.ndarray) else v)
          for k, v in solution.optimization_inputs.items()}
    oi["observations_board"][..., :2] = obs.mrcal_array()[..., :2]
    oi["do_apply_outlier_rejection"] = False
    mrcal.optimize(**oi)
    res, inlier, per_image, rms = residual_summary(obs, oi)
    return dataclasses.replace(solution, intrinsics=oi["intrinsics"][0].copy(), observations=obs,
                               optimization_inputs=oi, rms_px=rms, per_image_rms_px=per_image, residuals=res,
                               inlier=inlier, rejected_images=list(solution.rejected_images),
                               rejected_corners=list(solution.rejected_corners), notes=list(solution.notes))
