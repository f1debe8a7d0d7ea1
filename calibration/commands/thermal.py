"""`calibrate thermal`: thermal camera intrinsics from images of a heated checkerboard.

Detects the board in every image (with progress), writes corners.vnl, solves (mrcal, or OpenCV's
fisheye), and writes the model in every format with report.html, all into --out as one folder
(nothing is written when anything fails). Exit 0: the verdict is "trusted" (the whole image) or
"trusted-within-region" (usable inside the valid-intrinsics region written into the .cameramodel;
with --require-whole-image that exits 1 too); 1: it solved but the verdict is "not-trusted" (or the
data cannot be solved); 2: bad input. --exit-zero: 0 whenever it solved.
"""
from __future__ import annotations

import argparse
import logging
from pathlib import Path

import numpy as np

from platform_tools.rig import atomic
from platform_tools.rig.conventions import (CheckFailed, UserError, add_output_options, add_rig_options,
    print_json, rig_from_args)

from calibration.quiet import quiet_stderr
from calibration.report.verdict import MIN_TRUSTED_SHARE, TRUSTED, Verdict
from calibration.commands.synth import parse_board

log = logging.getLogger("calibration.thermal")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "thermal", help="thermal intrinsics from heated-checkerboard images (mrcal or OpenCV fisheye)",
        description="Calibrate a thermal camera's lens from images of a heated checkerboard. Writes into "
                    "--out: thermal.cameramodel (mrcal, with optimization_inputs), thermal_opencv.yaml, "
                    "thermal_camera_info.yaml (ROS), kalibr_camchain.yaml, corners.vnl and report.html "
                    "(coverage, residuals, projection uncertainty, per-image errors, verdict).",
        epilog="Verdict (report.html, --json verdict.grade): trusted (the whole image), trusted-within-region "
               "(usable inside the valid-intrinsics region written into thermal.cameramodel: the central 80% "
               f"of the image trusted and at least {100 * MIN_TRUSTED_SHARE:.0f}% of the whole image), not-trusted. "
               "Exit codes: 0 trusted or trusted-within-region; 1 not-trusted (or trusted-within-region with "
               "--require-whole-image), or not solvable; 2 bad input. --exit-zero: 0 whenever it solved.")
    add_rig_options(p)
    add_output_options(p)
    p.add_argument("--images", required=True, metavar="DIR|GLOB", help="folder or glob of 8/16-bit images")
    p.add_argument("--board", required=True, metavar="WxH", help="inner corners across x down, e.g. 10x7")
    p.add_argument("--square", required=True, type=float, metavar="METRES", help="square size in metres")
    p.add_argument("--out", required=True, type=Path, metavar="DIR", help="output folder (replaced whole)")
    p.add_argument("--lens-model", default=None, metavar="M",
                   help="opencv8 (default: right for a 95 deg lens, readable by ROS/OpenCV), splined, or a "
                        "full mrcal LENSMODEL_* name (--solver mrcal only)")
    p.add_argument("--solver", choices=("mrcal", "opencv"), default="mrcal",
                   help="mrcal (default; gives projection uncertainty) or opencv (cv2.fisheye, Kannala-Brandt)")
    p.add_argument("--exit-zero", action="store_true",
                   help="exit 0 even when the verdict is not-trusted (it stays in the report and --json)")
    p.add_argument("--require-whole-image", action="store_true",
                   help="exit 1 unless the verdict is 'trusted' over the whole image (a model trusted only "
                        "within its valid-intrinsics region fails too)")
    p.add_argument("--camera-name", default="thermal", help="camera name in the ROS/Kalibr files")
    p.set_defaults(handler=cmd_thermal)


def accepted(verdict: Verdict, *, require_whole_image: bool = False) -> bool:
    """Whether ``verdict`` exits 0 (before --exit-zero): trusted, or trusted within its region unless
    the whole image is required."""
    return verdict.grade == TRUSTED if require_whole_image else verdict.trustworthy


def _check_square(square: float) -> float:
    if not np.isfinite(square) or not 0.001 <= square <= 1.0:
        raise UserError(f"--square {square}: expected the square size in metres, 0.001 to 1 (e.g. 0.04)")
    return square


def detect(images: str, board: tuple[int, int], square_m: float):
    """Detection over the images: (observations, corners.vnl text). Corrupt files are bad input;
    saturated or blank images are skipped and named (all of them unusable is bad input too)."""
    from calibration.corners_io import BoardCorners, format_corners
    from calibration.detect import ImageError, detect_files, list_images
    from calibration.intrinsics.observations import from_detections
    try:
        files = list_images(images)
    except ImageError as exc:
        raise UserError(f"--images {exc}") from None
    results = detect_files(files, board, strict=False)
    bad = [r for r in results if r.detection is None]
    # ImageError reads "<path>: <what is wrong>"; judge the second part only
    what = {id(r): r.error[len(str(r.path)):] if r.error.startswith(str(r.path)) else r.error for r in bad}
    corrupt = [r for r in bad if "saturated" not in what[id(r)] and "same value" not in what[id(r)]]
    if corrupt:
        raise UserError(f"{corrupt[0].error}; remove it (and {len(corrupt) - 1} other such file(s))"
                        if len(corrupt) > 1 else f"{corrupt[0].error}; remove it or pass --images a glob "
                                                 f"that leaves it out")
    good = [r for r in results if r.detection is not None]
    if not good:
        raise UserError(f"--images {images}: none of the {len(results)} images is usable: {bad[0].error}")
    for r in bad:
        log.warning("skipped %s", r.error)
    sizes = {r.imagersize for r in good}
    if len(sizes) > 1:
        raise UserError(f"--images {images}: images of different sizes {sorted(sizes)}; one camera at a time")
    imagersize = sizes.pop()
    names = [r.path.name for r in good]
    dets = [r.detection.corners if r.detection.detected else None for r in good]
    wts = [r.detection.weight for r in good]
    obs = from_detections(names, dets, board, square_m, imagersize, wts)
    obs.missed.extend(r.path.name for r in bad)
    rows = [BoardCorners(r.path.name, r.detection.corners if r.detection.detected else None,
                         r.detection.level if r.detection.detected else None) for r in good]
    rows += [BoardCorners(r.path.name, None, None) for r in bad]
    if obs.n == 0:
        reasons = sorted({r.detection.reason for r in good if r.detection.reason})
        raise CheckFailed(f"--images {images}: no {board[0]}x{board[1]} board found in any of {len(results)} "
                          f"images ({'; '.join(reasons[:2]) or 'no detection'}); check --board (inner corners "
                          f"across x down) and that the board is warmer or cooler than the background")
    return obs, format_corners(rows)


def solve(obs, *, solver: str, lens_model: str | None, focal_px: float):
    from calibration.intrinsics import SolveError
    from calibration.intrinsics import mrcal_solver, opencv_solver
    from calibration.intrinsics.lensmodels import LensModelError
    try:
        if solver == "opencv":
            if lens_model is not None:
                raise UserError("--lens-model applies to --solver mrcal only (OpenCV's fisheye is Kannala-Brandt)")
            return opencv_solver.solve(obs, focal_px=focal_px)
        return mrcal_solver.solve(obs, lensmodel=lens_model, focal_px=focal_px)
    except LensModelError as exc:
        raise UserError(str(exc)) from None
    except SolveError as exc:
        raise CheckFailed(str(exc)) from None


def cmd_thermal(args: argparse.Namespace) -> int:
    from calibration.intrinsics import outputs
    rig = rig_from_args(args)
    board = parse_board(args.board)
    square = _check_square(args.square)
    spec = rig.camera_model(rig.desc.sensors.thermal.camera_model)
    focal = rig.focal_px(spec)
    if args.lens_model is not None:     # a bad name is bad input before any work is done
        from calibration.intrinsics.lensmodels import LensModelError, resolve
        try:
            resolve(args.lens_model, (spec.width_px, spec.height_px), 100.0)
        except LensModelError as exc:
            raise UserError(str(exc)) from None

    obs, corners_text = detect(args.images, board, square)
    if obs.imagersize != (spec.width_px, spec.height_px):
        log.warning("images are %dx%d, the rig description's thermal camera is %dx%d",
                    *obs.imagersize, spec.width_px, spec.height_px)
    with quiet_stderr(enabled=not args.verbose):
        solution = solve(obs, solver=args.solver, lens_model=args.lens_model, focal_px=focal)
        out = outputs.build(solution, camera_name=args.camera_name, rig_hash=rig.hash, corners_vnl=corners_text)
    with atomic.OutputDir(args.out) as stage:
        for name, text in out.files.items():
            (stage / name).write_text(text)
    summary = dict(out.summary, out=str(args.out), files=sorted(out.files))
    if args.json:
        print_json(summary)
    elif not args.quiet:
        print(f"{args.out}: {solution.solver} {solution.lensmodel}, {obs.n} images, RMS {solution.rms_px:.3f} px; "
              f"{out.verdict.headline}")
    if not accepted(out.verdict, require_whole_image=args.require_whole_image) and not args.exit_zero:
        need = "--require-whole-image: " if out.verdict.trustworthy else ""
        raise CheckFailed(f"{args.out}/report.html: {need}calibration {out.verdict.headline}")
    return 0
