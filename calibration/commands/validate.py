"""`calibrate validate MODEL --truth DIR`: how far a solved model is from the true lens."""
from __future__ import annotations

import argparse
from pathlib import Path

from platform_tools.rig.conventions import CheckFailed, UserError, add_output_options, print_json

from calibration.lens.compare import compare_models

# the accuracy targets on a "real" synthetic set (pixels)
TARGET_RMS_PX = 0.1
TARGET_CENTRAL_RMS_PX = 0.05


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "validate", help="compare a solved .cameramodel with the truth of a synthetic set",
        description="Compare MODEL with DIR/truth.cameramodel: focal and principal-point error, and the "
                    "projection difference over the whole image after the best-fit rotation (as mrcal's "
                    "projection_diff does): RMS and worst over the whole image and over its central 80%.",
        epilog=f"Exit 0 when within the targets (RMS <= {TARGET_RMS_PX} px over the image, <= "
               f"{TARGET_CENTRAL_RMS_PX} px over the central 80%), 1 when not, 2 on bad input.")
    add_output_options(p)
    p.add_argument("model", type=Path, metavar="MODEL", help="a .cameramodel (e.g. OUT/thermal.cameramodel)")
    p.add_argument("--truth", required=True, type=Path, metavar="DIR",
                   help="a synthetic set (holds truth.cameramodel), or a .cameramodel")
    p.add_argument("--max-rms", type=float, default=TARGET_RMS_PX, help="pass limit, whole image (px)")
    p.add_argument("--max-central-rms", type=float, default=TARGET_CENTRAL_RMS_PX,
                   help="pass limit, central 80%% (px)")
    p.add_argument("--exit-zero", action="store_true", help="exit 0 even when outside the targets")
    p.set_defaults(handler=cmd_validate)


def _load(path: Path, what: str):
    import mrcal
    if not path.is_file():
        raise UserError(f"{path}: no such file ({what})")
    try:
        return mrcal.cameramodel(str(path))
    except Exception as exc:
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise UserError(f"{path}: not a readable .cameramodel ({first[:120]})") from None


def cmd_validate(args: argparse.Namespace) -> int:
    truth_path = args.truth / "truth.cameramodel" if args.truth.is_dir() else args.truth
    model = _load(args.model, "the model to validate")
    truth = _load(truth_path, "the truth")
    try:
        c = compare_models(model, truth)
    except ValueError as exc:
        raise UserError(f"{args.model}: {exc}") from None
    ok = c.rms_px <= args.max_rms and c.central_rms_px <= args.max_central_rms
    result = dict(model=str(args.model), truth=str(truth_path), lensmodel=model.intrinsics()[0],
                  truth_lensmodel=truth.intrinsics()[0], **c.summary(),
                  targets=dict(rms_px=args.max_rms, central80_rms_px=args.max_central_rms), within_targets=ok)
    if args.json:
        print_json(result)
    elif not args.quiet:
        fe, pe = c.focal_error_px, c.principal_point_error_px
        print(f"focal error        fx {fe[0]:+.3f} px, fy {fe[1]:+.3f} px\n"
              f"principal point    cx {pe[0]:+.3f} px, cy {pe[1]:+.3f} px\n"
              f"projection diff    RMS {c.rms_px:.3f} px, worst {c.max_px:.3f} px (whole image, after a "
              f"{c.rotation_deg:.3f} deg best-fit rotation)\n"
              f"central 80%        RMS {c.central_rms_px:.3f} px, worst {c.central_max_px:.3f} px")
    if not ok and not args.exit_zero:
        raise CheckFailed(f"{args.model}: projection difference RMS {c.rms_px:.3f} px (limit {args.max_rms}) / "
                          f"central 80% {c.central_rms_px:.3f} px (limit {args.max_central_rms}): outside the targets")
    return 0
