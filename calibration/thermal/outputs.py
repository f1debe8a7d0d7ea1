"""Everything ``calibrate thermal`` writes, from a solution, as {file name: text}: the .cameramodel,
the OpenCV / ROS / Kalibr files, report.html; plus the verdict and a JSON-able summary."""
from __future__ import annotations

import io
from dataclasses import dataclass

import numpy as np

from platform_tools.rig.cameras import camera_model

from calibration import formats
from calibration.report import analysis, html, input_depth, missed
from calibration.report.validity import validity
from calibration.report.verdict import Verdict, judge
from calibration.intrinsics import crossval
from calibration.lens import kannala_brandt as kb
from calibration.lens.fit import imager_grid
from calibration.intrinsics.mrcal_solver import Solution
from calibration.thermal import lens_check


@dataclass
class Outputs:
    files: dict[str, str]
    summary: dict
    verdict: Verdict


def _cameramodel(solution: Solution, rational: formats.Representation | None):
    import mrcal
    if solution.lensmodel == kb.NAME:
        # mrcal has no Kannala-Brandt: write the nearest OPENCV8, without optimization_inputs
        p = np.concatenate([[rational.K[0, 0], rational.K[1, 1], rational.K[0, 2], rational.K[1, 2]], rational.D])
        return mrcal.cameramodel(intrinsics=("LENSMODEL_OPENCV8", p), imagersize=solution.imagersize)
    return solution.cameramodel()


def _cameramodel_text(model, note: str):
    buf = io.StringIO()
    model.write(buf, note=note)
    return buf.getvalue()


def build(solution: Solution, *, camera_name: str, rig_hash: str, corners_vnl: str,
          cross_validate: bool = True, nominal_corner_angle_deg: float = 0.0) -> Outputs:
    """``nominal_corner_angle_deg``: the angle the rig's nominal lens sees the image corners at; every
    exported model must stay radially monotonic out to it (and to the widest board corner seen)."""
    lens = kb.KannalaBrandt(solution.intrinsics, solution.imagersize) if solution.lensmodel == kb.NAME else \
        camera_model(solution.lensmodel, solution.intrinsics, solution.imagersize)
    ros = formats.nearest_for_ros(lens)
    ocv = formats.exact_or_nearest(lens)
    kal = formats.nearest_kalibr(lens)
    rational = formats.representation(lens, "rational_polynomial") if solution.lensmodel == kb.NAME else None
    note = (f"thermal intrinsics from calibrate thermal ({solution.solver}, {solution.lensmodel}), "
            f"rig hash {rig_hash[:12]}")
    if rational is not None:
        note += (f". NOT an mrcal solve: OpenCV fisheye (Kannala-Brandt) intrinsics "
                 f"{' '.join(f'{x:.9g}' for x in solution.intrinsics)} (fx fy cx cy k1 k2 k3 k4), expressed as "
                 f"the nearest LENSMODEL_OPENCV8 (a fit over the whole imager: RMS {rational.fit.rms_px:.3f} px, "
                 f"worst {rational.fit.max_px:.3f} px); no optimization_inputs, so no mrcal uncertainty. "
                 f"The exact model is in thermal_camera_info.yaml (equidistant) and kalibr_camchain.yaml")
    model = _cameramodel(solution, rational)

    obs = solution.observations
    cov = analysis.coverage(obs.corners, solution.inlier, solution.imagersize)
    unc = analysis.uncertainty(model, n_width=crossval.GRID_WIDTH) if solution.optimization_inputs else None
    cv = cv_error = None
    if cross_validate:
        try:
            cv = crossval.cross_validate(solution)
        except crossval.CrossValidationError as exc:
            cv_error = str(exc)
    grid = imager_grid(solution.imagersize, crossval.GRID_WIDTH)
    val = validity(grid, cov.points, solution.imagersize,
                   halves_diff_px=None if cv is None else cv.diff_px,
                   uncertainty_px=None if unc is None else unc.stdev_px)
    model.valid_intrinsics_region(val.region if len(val.region) >= 4 else np.zeros((0, 2)))
    cm_text = _cameramodel_text(model, note)
    files = {
        "thermal.cameramodel": cm_text,
        "thermal_opencv.yaml": formats.opencv_yaml(ocv, solution.imagersize, camera_name=camera_name,
                                                   rms_px=solution.rms_px),
        "thermal_camera_info.yaml": formats.ros_camera_info(ros, solution.imagersize, camera_name=camera_name),
        "kalibr_camchain.yaml": formats.kalibr_camchain(kal, solution.imagersize,
                                                        rostopic=f"/{camera_name}/image_raw"),
        "corners.vnl": corners_vnl,
    }
    lens_health = lens_check.exported_health(files, solution, min_corner_angle_deg=nominal_corner_angle_deg)
    verdict = judge(region_counts=cov.region_counts(), rms_px=solution.rms_px, n_images=obs.n,
                    n_rejected_images=len(solution.rejected_images),
                    uncertainty_central_px=None if unc is None else unc.central_max_px,
                    uncertainty_max_px=None if unc is None else unc.max_px,
                    validity=val, cross_validated=None if not cross_validate or cv_error else cv is not None,
                    lens_problems=lens_check.problems(lens_health), cross_validation_error=cv_error)
    depth = input_depth.note(obs.bit_depth)
    if depth is not None:
        verdict.warnings.append(depth.text)
    fmt = {"ROS camera_info": ros.summary(), "Kalibr camchain": kal.summary(),
           "OpenCV YAML": ocv.summary()}
    if rational is not None:
        fmt["thermal.cameramodel"] = rational.summary()
    summary = dict(
        solver=solution.solver, lensmodel=solution.lensmodel,
        intrinsics=[float(x) for x in solution.intrinsics],
        intrinsics_text=" ".join(f"{x:.6g}" for x in solution.intrinsics),
        imagersize=list(solution.imagersize), board=list(obs.board), square_m=obs.square_m,
        rms_px=solution.rms_px, n_images_used=obs.n, n_missed=len(obs.missed), missed=list(obs.missed),
        missed_why=[m.to_dict() for m in obs.missed_why], missed_causes=missed.counts(obs.missed_why),
        input_bit_depth=obs.bit_depth, input_note=None if depth is None else depth.text,
        n_rejected_images=len(solution.rejected_images),
        rejected_images=[dict(name=r.name, rms_px=r.rms_px, reason=r.reason) for r in solution.rejected_images],
        n_corners=int(solution.inlier.sum()), n_rejected_corners=len(solution.rejected_corners),
        rejected_corners=solution.rejected_corners,
        per_image=[dict(name=n, corners=int(c), rms_px=float(r))
                   for n, c, r in zip(obs.names, solution.inlier.sum(axis=1), solution.per_image_rms_px)],
        regions=cov.region_counts(),
        uncertainty=None if unc is None else dict(central_max_px=unc.central_max_px, max_px=unc.max_px,
                                                  observed_noise_px=unc.observed_noise_px),
        cross_validation=None if cv is None else cv.summary(), cross_validation_error=cv_error,
        validity=val.summary(), lens_health={name: h.summary() for name, h in lens_health.items()},
        formats=fmt, notes=list(solution.notes), model_choice=solution.model_choice,
        centroid_correction=solution.centroid_correction, rig_hash=rig_hash, verdict=verdict.to_dict())
    files["report.html"] = html.render(summary, verdict, html.plots(solution, cov, unc, cv, val))
    return Outputs(files, summary, verdict)
