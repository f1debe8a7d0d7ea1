"""`calibrate thermal`: thermal camera intrinsics from images of a heated checkerboard.

Parses, runs the pipeline (calibration/thermal/pipeline.py: detect the board in every image, solve with
mrcal or OpenCV's fisheye, the model in every format with report.html), writes it all into --out as one
folder (nothing is written when anything fails) and prints the verdict. Exit 0: the verdict is "trusted" (the whole image) or
"trusted-within-region" (usable inside the valid-intrinsics region written into the .cameramodel;
with --require-whole-image that exits 1 too); 1: it solved but the verdict is "not-trusted" (or the
data cannot be solved); 2: bad input. --exit-zero: 0 whenever it solved.
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from platform_tools.rig import atomic
from platform_tools.rig.conventions import (CheckFailed, UserError, add_output_options, add_rig_options,
                                            print_json, rig_from_args)

from calibration.report.verdict import MIN_TRUSTED_SHARE, TRUSTED, Verdict
from calibration.commands.synth import parse_board
from calibration.targets import TARGET_KINDS, TargetError


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "thermal", help="thermal intrinsics from heated-checkerboard images (mrcal or OpenCV fisheye)",
        description="Calibrate a thermal camera's lens from images of a heated checkerboard. Writes into "
                    "--out: thermal.cameramodel (mrcal, with optimization_inputs), thermal_opencv.yaml, "
                    "thermal_camera_info.yaml (ROS), kalibr_camchain.yaml, corners.vnl and report.html "
                    "(coverage, residuals, projection uncertainty, per-image errors, verdict). With --bag, the frames are "
                    "chosen from a recording (sharp, outside FFC, covering the image) and listed in frames.json.",
        epilog="Verdict (report.html, --json verdict.grade): trusted (the whole image), trusted-within-region "
               "(usable inside the valid-intrinsics region written into thermal.cameramodel: the central 80% "
               f"of the image trusted and at least {100 * MIN_TRUSTED_SHARE:.0f}% of the whole image), not-trusted. "
               "Exit codes: 0 trusted or trusted-within-region; 1 not-trusted (or trusted-within-region with "
               "--require-whole-image), or not solvable; 2 bad input. --exit-zero: 0 whenever it solved.")
    add_rig_options(p)
    add_output_options(p)
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--images", metavar="DIR|GLOB", help="folder or glob of 8/16-bit images")
    src.add_argument("--bag", type=Path, metavar="REC",
                     help="a recording (rosbag2 folder or MCAP): frames of --topic chosen by sharpness, FFC and "
                          "coverage (written as frames.json in --out)")
    p.add_argument("--topic", metavar="T", help="with --bag: the thermal image topic, e.g. /thermal_left/image")
    p.add_argument("--max-frames", type=int, default=40, metavar="N", help="with --bag: frames to calibrate from")
    p.add_argument("--board", required=True, metavar="WxH", help="inner corners across x down, e.g. 10x7")
    p.add_argument("--square", required=True, type=float, metavar="METRES", help="square size in metres")
    p.add_argument("--target", default="checkerboard", choices=TARGET_KINDS,
                   help="checkerboard (default); marker-checkerboard: a checkerboard with a plain central marker "
                        "over its 2x2 middle squares and one dot in the marker's top-left quarter, which labels "
                        "partial views with no board edge in them; circle-grid: W x H hot discs (OpenCV's "
                        "patternSize); asymmetric-circle-grid: --board is the lattice, W twice the discs per row "
                        "(OpenCV's (4, 11) is 8x11) (docs/calibration.md)")
    p.add_argument("--circle-radius", type=float, default=None, metavar="METRES",
                   help="circle grids: the discs' radius (default 0.3 x --square, the renderer's); each disc's "
                        "centroid is not its centre's projection, and the solve takes that bias off, iterated "
                        "with the lens and board poses it solves")
    p.add_argument("--no-centroid-correction", action="store_true",
                   help="circle grids: solve from the detected centroids as they are (to compare)")
    p.add_argument("--out", required=True, type=Path, metavar="DIR", help="output folder (replaced whole)")
    p.add_argument("--lens-model", default=None, metavar="M",
                   help="default: chosen by the data (OPENCV8 or OpenCV's Kannala-Brandt: a model with a pole or fold "
                        "inside the image is out, held-out views decide between healthy ones); or opencv8, splined, or a full mrcal LENSMODEL_* name "
                        "(--solver mrcal only)")
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


def nominal_corner_angle_deg(rig) -> float:
    """The off-axis angle at which the rig's nominal thermal lens (its focal length and HFoV, through the
    synthetic lens made from them) sees the image corners: every exported model must stay monotonic to it."""
    from calibration.formats.conversions import corner_angle_deg
    from calibration.synth.lens import nominal_thermal_lens
    try:
        return corner_angle_deg(nominal_thermal_lens(rig))
    except (KeyError, ValueError):
        return 0.0      # no fisheye profile fits this rig's thermal lens: the model's own field is used


def cmd_thermal(args: argparse.Namespace) -> int:
    rig = rig_from_args(args)
    board = parse_board(args.board)
    square = _check_square(args.square)
    try:
        from calibration.detect.targets import check_target_board
        check_target_board(args.target, board)
    except TargetError as exc:
        raise UserError(str(exc)) from None
    args.circle_radius_m = circle_radius(args, square)
    spec = rig.camera_model(rig.desc.sensors.thermal.camera_model)
    if args.topic and args.bag is None:
        raise UserError("--topic goes with --bag (a recording); --images reads image files")
    if args.bag is not None:
        if not args.topic:
            raise UserError("--bag needs --topic (the thermal image topic, e.g. /thermal_left/image)")
        if not 8 <= args.max_frames <= 1000:
            raise UserError(f"--max-frames {args.max_frames}: expected 8 to 1000")
        import json
        import tempfile
        from calibration.commands.thermal_frames import select_frames
        with tempfile.TemporaryDirectory(prefix="calibrate-frames-") as tmp:
            chosen = select_frames(args.bag, args.topic, board, args.target, rig, Path(tmp), args.max_frames)
            obs, solution, out = _calibrate(args, rig, spec, tmp, board, square)
        out.files["frames.json"] = json.dumps(chosen, indent=1)
        out.summary["frames"] = {k: v for k, v in chosen.items() if k != "chosen_stamps_ns"}
    else:
        obs, solution, out = _calibrate(args, rig, spec, args.images, board, square)
    return _write_and_report(args, obs, solution, out)


def circle_radius(args, square: float) -> float | None:
    """The disc radius whose centroid bias the solve takes off (None: not a circle grid, or
    --no-centroid-correction); a radius the board cannot have is bad input."""
    from calibration.intrinsics.circle_bias import CircleBiasError, check_radius
    from calibration.targets.spec import CIRCLE_KINDS, CIRCLE_RADIUS_SPACING
    if args.target not in CIRCLE_KINDS:
        if args.circle_radius is not None:
            raise UserError(f"--circle-radius goes with --target circle-grid or asymmetric-circle-grid, "
                            f"not {args.target}")
        return None
    if args.no_centroid_correction:
        return None
    try:
        return check_radius(CIRCLE_RADIUS_SPACING * square if args.circle_radius is None else args.circle_radius,
                            square)
    except CircleBiasError as exc:
        raise UserError(str(exc)) from None


def _calibrate(args, rig, spec, images, board, square):
    from calibration.thermal.pipeline import calibrate
    return calibrate(images, board, square, solver=args.solver, lens_model=args.lens_model,
                     focal_px=rig.focal_px(spec), expected_size=(spec.width_px, spec.height_px),
                     camera_name=args.camera_name, rig_hash=rig.hash, show_solver_output=args.verbose,
                     nominal_corner_angle_deg=nominal_corner_angle_deg(rig), target=args.target,
                     circle_radius_m=args.circle_radius_m)


def _write_and_report(args, obs, solution, out) -> int:
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
