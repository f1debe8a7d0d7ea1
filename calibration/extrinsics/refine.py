"""``calibrate rig``'s work: the seed lenses, the joint solve with its two halves, how far the solved rig
is from CAD and the RGB-to-thermal reprojection it implies (docs/extrinsics.md). Poses in mm and deg,
pixels in px; every lens is an ``mrcal.cameramodel``."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from platform_tools.rig.cameras import ImageSizeError, imagersize, scaled
from platform_tools.rig.conventions import CheckFailed, UserError

from calibration.extrinsics.cad import CAMERAS, FrameTree
from calibration.extrinsics.outputs import nominal_lenses, pose_dict
from calibration.extrinsics.sets import RigObservations
from calibration.extrinsics.solve import (RigSolution, RigSolveError, difference, mapping_error_px,
                                          rgb_to_thermal_px, solve_rig)
from calibration.synth.lens import nominal_thermal_lens

DEPTHS_M = (1.5, 5.0)      # the depths the RGB-to-thermal reprojection is reported at
MIN_SETS_FOR_HALVES = 8    # fewer sets: no cross-validation of the extrinsics


def zed_seed(rig, short: str, size: tuple[int, int], models: Path | None):
    """The seed lens (an mrcal.cameramodel) of a ZED camera (``zed_left`` / ``zed_right``) for its images of
    ``size`` (W, H): ``models/<short>.cameramodel`` (or ``zed_x_left...``) when ``models`` is given, else the
    rig's nominal pinhole scaled to the images; UserError naming the file or the size when neither fits."""
    if models is not None:
        import mrcal
        cands = [models / f"{short}.cameramodel", models / f"{short.replace('zed_', 'zed_x_')}.cameramodel"]
        path = next((c for c in cands if c.is_file()), None)
        if path is None:
            raise UserError(f"--zed-models {models}: no {cands[0].name} (or {cands[1].name})")
        try:
            m = mrcal.cameramodel(str(path))
        except Exception as exc:  # mrcal raises plain Exceptions for bad files
            raise UserError(f"{path}: not an mrcal .cameramodel ({str(exc).splitlines()[0][:120]})") from None
        if tuple(int(x) for x in m.imagersize()) != tuple(size):
            raise UserError(f"{path}: the model is {m.imagersize()[0]}x{m.imagersize()[1]}, the {short} images are "
                            f"{size[0]}x{size[1]}")
        return m
    nom = nominal_lenses(rig)[short]
    try:
        return scaled(nom, size, what=f"{short}/ images (not the rig's ZED at any scale; give --zed-models)")
    except ImageSizeError as exc:
        raise UserError(str(exc)) from None


def thermal_seed(rig, short: str, size: tuple[int, int]):
    """The seed lens of a thermal camera: the nominal synthetic-lens model of the rig (an mrcal.cameramodel,
    OPENCV8); UserError when the images are not the rig's thermal imager size."""
    lens = nominal_thermal_lens(rig, short)
    if imagersize(lens) != tuple(size):
        raise UserError(f"{short}/ images are {size[0]}x{size[1]}; the rig's thermal camera is "
                        f"{imagersize(lens)[0]}x{imagersize(lens)[1]}")
    return lens


def seeds(rig, obs: RigObservations, zed_models: Path | None) -> dict:
    """camera short name -> its seed lens for the images of ``obs``."""
    return {c: (zed_seed(rig, c, obs.imagersizes[c], zed_models) if c.startswith("zed") else
                thermal_seed(rig, c, obs.imagersizes[c])) for c in CAMERAS}


def solve_with_halves(obs: RigObservations, seed_lenses: dict, cad: FrameTree, *,
                      zed_intrinsics: str, prior: dict | None = None) -> tuple[RigSolution, list[RigSolution] | None]:
    """The joint solve of all sets, and of the even and the odd sets (None below MIN_SETS_FOR_HALVES sets),
    each with ``prior`` (camera -> covariance, :func:`calibration.extrinsics.solve.solve_rig`); CheckFailed
    with one line when mrcal cannot solve it."""
    try:
        sol = solve_rig(obs, seed_lenses, cad, zed_intrinsics=zed_intrinsics, prior=prior)
        halves = None
        if obs.n >= MIN_SETS_FOR_HALVES:
            idx = np.arange(obs.n)
            halves = [solve_rig(obs.subset(idx % 2 == k), seed_lenses, cad, zed_intrinsics=zed_intrinsics,
                                prior=prior) for k in (0, 1)]
    except RigSolveError as exc:
        raise CheckFailed(str(exc)) from None
    except Exception as exc:   # mrcal reports a singular problem as a bare exception
        if "mrcal" not in type(exc).__module__ and not isinstance(exc, (ValueError, np.linalg.LinAlgError)):
            raise
        raise CheckFailed(f"the joint solve failed ({str(exc).splitlines()[0][:160]}); more sets, or boards "
                          f"nearer the cameras") from None
    return sol, halves


def differences_from_cad(cad: FrameTree, tree: FrameTree, *, tolerance_mm: float,
                         tolerance_deg: float) -> tuple[dict, list[str]]:
    """Per camera: how far the solved pose (``tree``) is from CAD (mm, deg, in rig axes and in the camera's
    own frame), and one warning per camera beyond the tolerances."""
    diffs, warnings = {}, []
    for c, frame in CAMERAS.items():
        mm, deg, D = difference(cad.T_rig[frame], tree.T_rig[frame])
        dr = tree.T_rig[frame].t - cad.T_rig[frame].t
        diffs[c] = {"mm": mm, "deg": deg, "rig_axes_mm": [float(x) for x in dr],
                    "in_camera_frame": pose_dict(D), "anchor": c == "zed_left"}
        if mm > tolerance_mm or deg > tolerance_deg:
            warnings.append(f"{c} is {mm:.2f} mm and {deg:.3f} deg from its CAD pose (tolerance {tolerance_mm:g} "
                            f"mm, {tolerance_deg:g} deg): check how it is mounted")
    return diffs, warnings


#: a built rig's camera is within this Mahalanobis distance of its CAD pose with 99.73 % probability under
#: the stack-up prior (chi-square, 6 degrees of freedom: the "3 sigma" of one axis)
PRIOR_LIMIT_SIGMA = 4.48


def prior_distance(cad: FrameTree, tree: FrameTree, priors: dict) -> tuple[dict[str, float], list[str]]:
    """Per camera with a prior: how many sigmas (Mahalanobis distance under its stack-up covariance) its
    solved pose is from CAD relative to the ZED left camera, and a warning beyond PRIOR_LIMIT_SIGMA: the
    camera sits further from CAD than the tolerances allow, so the prior pulls the solve towards CAD."""
    out, warnings = {}, []
    zl = CAMERAS["zed_left"]
    for c, pr in priors.items():
        D = cad.T(zl, CAMERAS[c]).inverse() @ tree.T(zl, CAMERAS[c])
        xi = np.concatenate([D.t, D.rt()[:3]])
        m = float(np.sqrt(xi @ np.linalg.solve(pr.covariance_optical + 1e-12 * np.eye(6), xi)))
        out[c] = m
        if m > PRIOR_LIMIT_SIGMA:
            warnings.append(f"{c} is {m:.1f} sigma from its CAD pose under the tolerance stack-up (a built rig is within "
                            f"{PRIOR_LIMIT_SIGMA:g} with 99.7 %): the prior pulls it towards CAD; check how it is mounted, "
                            f"or solve with --prior none")
    return out, warnings


def reprojection(cad: FrameTree, sol: RigSolution, halves: list[RigSolution] | None = None) -> dict:
    """Per thermal camera and depth: where a ZED left pixel's point lands in the thermal image through
    the CAD extrinsics against through the refined ones (px), and the refined extrinsics' own error,
    estimated by cross-validation (two solves on the even and the odd sets: half the difference of their
    extrinsics, both through the full solve's lenses)."""
    out = {}
    zl = CAMERAS["zed_left"]
    for th in ("thermal_left", "thermal_right"):
        rows = {}
        for d in DEPTHS_M:
            ref = rgb_to_thermal_px(sol.lenses["zed_left"], sol.lenses[th], sol.T_ref_cam[th].inverse(), d)
            cadq = rgb_to_thermal_px(sol.lenses["zed_left"], sol.lenses[th], cad.T(CAMERAS[th], zl), d)
            row = {"cad_vs_refined": mapping_error_px(ref, cadq)}
            if halves is not None:
                # the halves' extrinsics through the full solve's lenses: the extrinsics' own spread
                a, b = (rgb_to_thermal_px(sol.lenses["zed_left"], sol.lenses[th], h.T_ref_cam[th].inverse(), d)
                        for h in halves)
                e = mapping_error_px(a, b)
                row["refined_cross_validation"] = {"rms_px": e["rms_px"] / 2, "max_px": e["max_px"] / 2,
                                                   "points": e["points"]}
            rows[f"{d:g}m"] = row
        out[th] = rows
    return out


