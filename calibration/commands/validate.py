"""`calibrate validate MODEL --truth DIR`: how far a solved model is from the true lens."""
from __future__ import annotations

import argparse
from pathlib import Path

from platform_tools.rig.conventions import CheckFailed, UserError, add_output_options, print_json

from calibration.lens.compare import compare

# the accuracy targets on a "real" synthetic set (pixels)
TARGET_RMS_PX = 0.1
TARGET_CENTRAL_RMS_PX = 0.05


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "validate", help="compare a solved .cameramodel with the truth of a synthetic set",
        description="Compare MODEL with the truth of a synthetic set: DIR/truth.cameramodel (read by mrcal), "
                    "or for a Kannala-Brandt truth lens DIR/truth_fisheye.yaml (read by cv2.FileStorage and "
                    "unprojected by cv2.fisheye): focal and principal-point error, and the "
                    "projection difference over the whole image after the best-fit rotation (as mrcal's "
                    "projection_diff does): RMS and worst over the whole image and over its central 80%.",
        epilog=f"Exit 0 when within the targets (RMS <= {TARGET_RMS_PX} px over the image, <= "
               f"{TARGET_CENTRAL_RMS_PX} px over the central 80%), 1 when not, 2 on bad input.")
    add_output_options(p)
    p.add_argument("model", type=Path, metavar="MODEL", help="a .cameramodel (e.g. OUT/thermal.cameramodel)")
    p.add_argument("--truth", required=True, type=Path, metavar="DIR",
                   help="a synthetic set (holds truth.cameramodel or truth_fisheye.yaml), or one such file")
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


def _load_fisheye_truth(path: Path):
    """(unproject, imagersize, core fx fy cx cy, label) of an OpenCV fisheye YAML (truth_fisheye.yaml),
    unprojected by cv2.fisheye itself (calibration/formats/readback.py), not by our Kannala-Brandt code."""
    import cv2
    import numpy as np
    from calibration.formats.readback import opencv_pair
    try:
        fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
        K = fs.getNode("camera_matrix").mat()
        D = fs.getNode("distortion_coefficients").mat()
        w, h = int(fs.getNode("image_width").real()), int(fs.getNode("image_height").real())
        fs.release()
    except cv2.error:
        K = D = None
        w = h = 0
    if K is None or D is None or K.shape != (3, 3) or D.size != 4 or w <= 0 or h <= 0:
        raise UserError(f"{path}: not a cv2.fisheye truth: expected camera_matrix (3x3), distortion_coefficients "
                        f"(4: k1..k4), image_width and image_height (as calibrate synth writes truth_fisheye.yaml)")
    _, unproject = opencv_pair(K, D, fisheye=True)

    def unit(q):
        v = unproject(np.asarray(q, dtype=float).reshape(-1, 2))
        return v / np.linalg.norm(v, axis=-1, keepdims=True)
    return unit, (w, h), np.array([K[0, 0], K[1, 1], K[0, 2], K[1, 2]]), "KANNALA_BRANDT (cv2.fisheye)"


def _load_truth(arg: Path):
    """The truth of ``--truth``: (unproject, imagersize, core, lensmodel label, path)."""
    import numpy as np
    path = arg
    if arg.is_dir():
        path = next((arg / n for n in ("truth.cameramodel", "truth_fisheye.yaml") if (arg / n).is_file()),
                    arg / "truth.cameramodel")
        if not path.is_file():
            raise UserError(f"--truth {arg}: no truth.cameramodel or truth_fisheye.yaml in it (a set "
                            f"written by calibrate synth holds one of them)")
    if path.suffix in (".yaml", ".yml"):
        if not path.is_file():
            raise UserError(f"{path}: no such file (the truth)")
        return (*_load_fisheye_truth(path), path)
    truth = _load(path, "the truth")
    lt, it = truth.intrinsics()
    return (lambda q: mrcal_unproject(q, lt, it), tuple(int(x) for x in truth.imagersize()),
            np.asarray(it[:4], float), lt, path)


def mrcal_unproject(q, lensmodel, intrinsics):
    import mrcal
    import numpy as np
    return mrcal.unproject(np.ascontiguousarray(q, dtype=float), lensmodel, intrinsics, normalize=True)


def cmd_validate(args: argparse.Namespace) -> int:
    import mrcal
    import numpy as np
    model = _load(args.model, "the model to validate")
    unproject, size, core_truth, truth_lm, truth_path = _load_truth(args.truth)
    lm, intr = model.intrinsics()
    if tuple(model.imagersize()) != tuple(size):
        raise UserError(f"{args.model}: imager sizes differ: {tuple(model.imagersize())} vs truth {tuple(size)} "
                        f"({truth_path})")
    c = compare(lambda v: mrcal.project(np.ascontiguousarray(v), lm, intr), unproject, size,
                core=intr[:4], core_truth=core_truth)
    result = dict(model=str(args.model), truth=str(truth_path), lensmodel=lm,
                  truth_lensmodel=truth_lm, **c.summary(),
                  targets=dict(rms_px=args.max_rms, central80_rms_px=args.max_central_rms), within_targets=None)
    ok = c.rms_px <= args.max_rms and c.central_rms_px <= args.max_central_rms
    result["within_targets"] = ok
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
