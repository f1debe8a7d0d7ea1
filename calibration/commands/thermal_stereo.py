"""`calibrate thermal-stereo`: the thermal pair's left-right pose from board views both cameras saw,
seeded from the two mono models and the CAD pose between the cameras; the pair as two .cameramodel
files, mrcal's rectification (models and maps) and the epipolar error (docs/calibration.md,
"calibrate thermal-stereo"). Parses, calls calibration/stereo, prints."""
from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

from platform_tools.rig import atomic
from platform_tools.rig.conventions import (CheckFailed, UserError, add_output_options, add_rig_options,
                                            print_json, rig_from_args)
from platform_tools.rig.progress import progress

from calibration.commands.synth import parse_board
from calibration.commands.thermal import circle_radius
from calibration.targets import TARGET_KINDS

DEFAULT_MAX_EPIPOLAR_RMS_PX = 0.5
DEFAULT_TOLERANCE_MM = 5.0          # as `calibrate rig`: a camera further from CAD is probably mounted wrongly
DEFAULT_TOLERANCE_DEG = 1.0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "thermal-stereo", help="the thermal stereo pair: left-right pose, rectification maps, epipolar error",
        description="Detect the board in DIR/left/ and DIR/right/ (or DIR/thermal_left/ and DIR/thermal_right/), "
                    "one image per board pose in each, paired by file name; solve the right camera's pose in the "
                    "left optical frame with mrcal from the views both saw, seeded from the two mono models "
                    "(--left, --right: .cameramodel files, e.g. from `calibrate thermal`; their lenses are held "
                    "unless --refine-intrinsics) and the CAD pose between the thermal cameras. Writes into --out: "
                    "left.cameramodel and right.cameramodel (extrinsics: the left optical frame is the reference), "
                    "rectified_left/right.cameramodel (mrcal.rectified_system, LATLON), rectification_left/right.npy "
                    "(float32 (H, W, 2) maps for cv2.remap(img, map, None, cv2.INTER_LINEAR)) and stereo.json "
                    "(pose, difference from CAD, RMS, epipolar error: the rectified-row difference of matched "
                    "corners, RMS and p99, after and before the solve). For a Kannala-Brandt pair (--left-fisheye / "
                    "--right-fisheye, or thermal_opencv.yaml beside each model when both are fisheye) stereo.json "
                    "also holds the cross-check with cv2.fisheye.stereoCalibrate / stereoRectify on the same "
                    "corners (opencv_fisheye_cross_check: pose, rectifying rotations, epipolar error).",
        epilog="Exit codes: 0 solved, the epipolar RMS within --max-epipolar-rms (a pose beyond the tolerance "
               "from CAD is a warning); 1 solved but the epipolar RMS above it (outputs written); 2 bad input "
               "(a missing model or image, an image without its partner, models of different imager sizes or "
               "lens models, an image of another size than its model, fewer than --min-views shared views, "
               "a --left-fisheye / --right-fisheye that is not an OpenCV fisheye camera of the model's size, "
               "a camera's views that --board cannot be the board of: grids larger than it, or labels placed "
               "by opposite board edges with no view showing both; a --bag without the ZED left images or "
               "whose trigger assignment is ambiguous; 1 also: no pair of the --bag shows the board to both).")
    p.add_argument("--left", required=True, type=Path, metavar="L.cameramodel", help="the left camera's mono model")
    p.add_argument("--right", required=True, type=Path, metavar="R.cameramodel", help="the right camera's mono model")
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--images", type=Path, metavar="DIR",
                     help="folder with left/ and right/ (or thermal_left/ and thermal_right/), paired by name")
    src.add_argument("--bag", type=Path, metavar="REC",
                     help="a recording instead: the two Bosons' frames paired by the trigger that exposed them (as "
                          "export pairs them, never by the nearest stamps), neither in an FFC, the board found in "
                          "both, sharp, covering the image; stereo.json says which (the recording needs the ZED left "
                          "images: the triggers are numbered on its clock)")
    p.add_argument("--board", required=True, metavar="WxH", help="inner corners across x down, e.g. 10x7")
    p.add_argument("--square", required=True, type=float, metavar="METRES", help="square size in metres")
    p.add_argument("--target", default="checkerboard", choices=TARGET_KINDS, help="the board (as calibrate thermal)")
    p.add_argument("--out", required=True, type=Path, metavar="DIR", help="output folder (replaced whole)")
    p.add_argument("--left-fisheye", type=Path, metavar="L.yaml",
                   help="the left camera's exact Kannala-Brandt lens (thermal_opencv.yaml of `calibrate thermal "
                        "--solver opencv`, distortion_model fisheye): the pair is then cross-checked with "
                        "cv2.fisheye.stereoCalibrate / stereoRectify (default: thermal_opencv.yaml beside each "
                        "model when both are fisheye)")
    p.add_argument("--right-fisheye", type=Path, metavar="R.yaml", help="the right camera's (as --left-fisheye)")
    p.add_argument("--circle-radius", type=float, default=None, metavar="METRES",
                   help="circle grids: the discs' radius (default 0.3 x --square); each disc's centroid bias is "
                        "taken off in both cameras, iterated with the pose solved (as calibrate thermal does)")
    p.add_argument("--no-centroid-correction", action="store_true",
                   help="circle grids: solve from the detected centroids as they are (to compare)")
    p.add_argument("--refine-intrinsics", action="store_true",
                   help="solve both lenses jointly with the pose (default: held at the mono models)")
    p.add_argument("--min-views", type=int, default=None, metavar="N",
                   help="board poses both cameras must see (default 5)")
    p.add_argument("--max-epipolar-rms", type=float, default=DEFAULT_MAX_EPIPOLAR_RMS_PX, metavar="PX",
                   help=f"exit 1 above this epipolar RMS (default {DEFAULT_MAX_EPIPOLAR_RMS_PX})")
    p.add_argument("--tolerance-mm", type=float, default=DEFAULT_TOLERANCE_MM,
                   help=f"warn when the pose is further than this from CAD (default {DEFAULT_TOLERANCE_MM:g} mm)")
    p.add_argument("--tolerance-deg", type=float, default=DEFAULT_TOLERANCE_DEG,
                   help=f"warn when the pose is turned more than this from CAD (default {DEFAULT_TOLERANCE_DEG:g} deg)")
    add_rig_options(p)
    add_output_options(p)
    p.set_defaults(handler=cmd_thermal_stereo)


def read_model(path: Path, what: str):
    import mrcal
    if not path.is_file():
        raise UserError(f"{what} {path}: no such file")
    try:
        return mrcal.cameramodel(str(path))
    except Exception as exc:      # mrcal raises plain Exceptions for bad files
        raise UserError(f"{path}: not an mrcal .cameramodel ({str(exc).splitlines()[0][:120] if str(exc) else exc})") \
            from None


def check_models(left, right, paths: tuple[Path, Path]) -> None:
    """UserError unless the two mono models can be one mrcal problem: same imager size and lens model."""
    sl, sr = tuple(left.imagersize()), tuple(right.imagersize())
    if sl != sr:
        raise UserError(f"{paths[1]}: a {sr[0]}x{sr[1]} model, {paths[0]} is {sl[0]}x{sl[1]}; the two thermal "
                        f"cameras of the pair have one imager size: give each camera's own model")
    lm, rm = left.intrinsics()[0], right.intrinsics()[0]
    if lm != rm:
        raise UserError(f"{paths[1]}: lens model {rm}, {paths[0]} is {lm}; mrcal solves one lens model for both "
                        f"cameras: calibrate both with the same --lens-model")


def fisheye_lenses(args, models):
    """(left Fisheye, right Fisheye, (paths)) for the OpenCV cross-check, or None: --left-fisheye and
    --right-fisheye, else thermal_opencv.yaml beside each model when both are fisheye. Bad input: one
    of the two flags only, an unreadable or non-fisheye file given, a size other than its model's."""
    from calibration.stereo.fisheye_check import FisheyeFileError, read_fisheye
    given = (args.left_fisheye, args.right_fisheye)
    if (given[0] is None) != (given[1] is None):
        raise UserError("--left-fisheye and --right-fisheye go together (one lens file per camera)")
    paths = given if given[0] is not None else tuple(m.parent / "thermal_opencv.yaml" for m in (args.left, args.right))
    try:
        lenses = tuple(read_fisheye(p) for p in paths)
    except FisheyeFileError as exc:
        if given[0] is None:
            return None           # not a Kannala-Brandt pair: nothing to cross-check
        raise UserError(f"{exc}; nothing written") from None
    for p, f, m in zip(paths, lenses, models):
        if tuple(f.size) != tuple(int(x) for x in m.imagersize()):
            raise UserError(f"{p}: a {f.size[0]}x{f.size[1]} camera, its model is "
                            f"{m.imagersize()[0]}x{m.imagersize()[1]}; give each camera's own files")
    return lenses[0], lenses[1], paths


def cross_check_line(check: dict) -> str:
    """One line of the OpenCV fisheye cross-check for the terminal."""
    if check.get("errors") and "rectification" not in check:
        return f"cv2.fisheye cross-check: {'; '.join(check['errors'])}"
    r, rows = check["rectification"], check["epipolar_opencv_rectification"]["rows"]
    pose = check.get("pose")
    at = (f"; cv2.fisheye.stereoCalibrate's pose {pose['translation_mm']:.3f} mm and {pose['rotation_deg']:.4f} deg "
          f"from ours") if pose else f"; {'; '.join(check['errors'])}"
    return (f"cv2.fisheye cross-check: stereoRectify's rotations {r['rotation_left_deg']:.4f} / "
            f"{r['rotation_right_deg']:.4f} deg from ours (baseline axis {r['baseline_axis_deg']:.4f} deg), "
            f"epipolar RMS through it {rows['rms_px']:.3f} px (ours {check['epipolar_ours']['rms_px']:.3f})" + at)


def detect_pairs(pairs, board, square, target, sizes, quiet: bool):
    """StereoObservations of every (name, left, right) pair; UserError for an unreadable image or one of
    another size than its model, and for a camera's views that --board cannot be the board of
    (calibration/detect/batch.board_size_problem, as `calibrate thermal` refuses them: here a view
    labelled from the board's other edge in one camera than in the other would give the one board
    pose the two share two different places)."""
    from calibration.detect import ImageError, detect_target, load_image
    from calibration.detect.batch import FileDetection, board_size_problem
    from calibration.stereo.pairs import from_detections
    found = {0: [], 1: []}
    items = pairs if quiet else progress(pairs, desc="detecting pairs", total=len(pairs), unit="pair")
    for name, *files in items:
        for side, f in enumerate(files):
            try:
                img = load_image(f)
            except ImageError as exc:
                raise UserError(f"{exc}; nothing written") from None
            W, H = (int(x) for x in sizes[side])
            if (img.shape[1], img.shape[0]) != (W, H):
                raise UserError(f"{f}: {img.shape[1]}x{img.shape[0]} image, its model is for {W}x{H}; "
                                f"nothing written")
            found[side].append(FileDetection(Path(f), detect_target(img, board, target), "", (W, H), target))
    for side in (0, 1):
        why = board_size_problem(found[side], board)
        if why:
            raise UserError(f"{Path(pairs[0][1 + side]).parent}: {why}; nothing written")
    dets = {side: [r.detection if r.detection.detected else None for r in found[side]] for side in (0, 1)}
    return from_detections([p[0] for p in pairs], dets[0], dets[1], board, square)


def cmd_thermal_stereo(args: argparse.Namespace) -> int:
    import mrcal

    from calibration.commands.extrinsics import frames_or_user_error
    from calibration.extrinsics.cad import CAMERAS
    from calibration.stereo import rectify
    from calibration.stereo.outputs import all_files
    from calibration.stereo.pairs import StereoInputError, find_pairs
    from calibration.stereo.solve import MIN_SHARED_VIEWS, StereoSolveError, pose_difference, solve_pair

    rig = rig_from_args(args)
    board = parse_board(args.board)
    if not np.isfinite(args.square) or not 0.001 <= args.square <= 1.0:
        raise UserError(f"--square {args.square}: expected the square size in metres, 0.001 to 1 (e.g. 0.04)")
    min_views = MIN_SHARED_VIEWS if args.min_views is None else args.min_views
    if min_views < 3:
        raise UserError(f"--min-views {min_views}: at least 3 (a pose needs views from several directions)")
    for name in ("max_epipolar_rms", "tolerance_mm", "tolerance_deg"):
        if not getattr(args, name) > 0:
            raise UserError(f"--{name.replace('_', '-')} {getattr(args, name)}: must be > 0")
    radius_m = circle_radius(args, args.square)
    left, right = read_model(args.left, "--left"), read_model(args.right, "--right")
    check_models(left, right, (args.left, args.right))
    fisheye = fisheye_lenses(args, (left, right))
    with tempfile.TemporaryDirectory(prefix="thermal-stereo-") as tmp:
        frames = None
        images = args.images
        if args.bag is not None:
            from calibration.commands.stereo_frames import select_pairs
            images = Path(tmp)
            frames = select_pairs(args.bag, board, args.target, rig, images)
        try:
            pairs = find_pairs(images)
        except StereoInputError as exc:
            raise UserError(f"{exc}; nothing written") from None
        obs = detect_pairs(pairs, board, args.square, args.target, (left.imagersize(), right.imagersize()),
                           args.quiet)
    where = args.bag if args.bag is not None else args.images

    tree = frames_or_user_error(rig)
    T_seed = tree.T(CAMERAS["thermal_left"], CAMERAS["thermal_right"])       # right optical frame in the left
    rt_seed = T_seed.inverse().rt(metres=True)
    lenses = tuple(mrcal.cameramodel(intrinsics=m.intrinsics(), imagersize=m.imagersize()) for m in (left, right))
    try:
        sol = solve_pair(obs, lenses, rt_seed, refine_intrinsics=args.refine_intrinsics, min_views=min_views,
                         verbose=args.verbose > 0)
    except StereoSolveError as exc:
        raise UserError(f"{where}: {exc}; nothing written") from None

    shared = obs.subset(obs.shared())
    correction = None
    if radius_m is not None:
        from calibration.stereo.centroids import solve_pair_corrected
        sol, shared, correction = solve_pair_corrected(obs, sol, radius_m, verbose=args.verbose > 0)
    rect = rectify.rectified_models(sol.models)
    maps = rectify.rectification_maps(sol.models, rect)
    epi = rectify.epipolar_stats(rectify.row_disparity(sol.models, rect, shared.left, shared.right))
    seed_models = (lenses[0], mrcal.cameramodel(intrinsics=lenses[1].intrinsics(), imagersize=lenses[1].imagersize(),
                                                extrinsics_rt_fromref=rt_seed))
    seed_rect = rectify.rectified_models(seed_models)
    epi_seed = rectify.epipolar_stats(rectify.row_disparity(seed_models, seed_rect, shared.left, shared.right))
    diff = pose_difference(T_seed, sol.T_left_right)
    check = None
    if fisheye is not None:
        from calibration.stereo.fisheye_check import cross_check
        check = dict(cross_check(*fisheye[:2], shared.left, shared.right, shared.board_points_m(),
                                 sol.rt_right_left, rect, epi), files=[str(f) for f in fisheye[2]])
    warnings = []
    if diff["translation_mm"] > args.tolerance_mm or diff["rotation_deg"] > args.tolerance_deg:
        warnings.append(f"the right camera is {diff['translation_mm']:.2f} mm and {diff['rotation_deg']:.3f} deg "
                        f"from its CAD pose relative to the left (tolerance {args.tolerance_mm:g} mm, "
                        f"{args.tolerance_deg:g} deg): a camera mounted wrongly, or the wrong model given")
    report = {
        "convention": "T_left_right: the right optical frame in the left one (mm); rt_right_left: mrcal rt "
                      "(left -> right, metres), the right model's extrinsics_rt_fromref",
        "images": None if args.images is None else str(args.images), "bag_frames": frames,
        "left_model": str(args.left), "right_model": str(args.right),
        "board": {"width": board[0], "height": board[1], "square_m": args.square, "target": args.target},
        "pairs": obs.n, "shared_views": sol.n_views,
        "not_shared": [n for n, s in zip(obs.names, obs.shared()) if not s],
        "intrinsics": "refined jointly" if sol.refined_intrinsics else "held at the mono models",
        "lensmodel": sol.models[0].intrinsics()[0], "rms_px": {"left": sol.rms_px[0], "right": sol.rms_px[1]},
        "outliers": sol.n_outliers, "rt_right_left": [float(x) for x in sol.rt_right_left],
        "T_left_right": {"xyz_mm": diff["xyz_mm"], "rpy_deg": [float(x) for x in sol.T_left_right.rpy_deg()]},
        "from_cad": diff, "epipolar": epi, "epipolar_at_cad": epi_seed,
        "rectified": {"lensmodel": rect[0].intrinsics()[0], "imagersize": [int(x) for x in rect[0].imagersize()],
                      "baseline_mm": diff["baseline_mm"]},
        "centroid_correction": correction,
        "opencv_fisheye_cross_check": check, "warnings": warnings, "rig_hash": rig.hash, "out": str(args.out)}
    files = all_files(sol.models, rect, maps, report, seed_note="seeded from the CAD pose")
    with atomic.OutputDir(args.out) as stage:
        for name, data in files.items():
            (stage / name).write_bytes(data)
    report["files"] = sorted(files)
    if args.json:
        print_json(report)
    elif not args.quiet:
        x, y, z = diff["xyz_mm"]
        print(f"{args.out}: {sol.n_views} shared views, RMS {sol.rms_px[0]:.3f} / {sol.rms_px[1]:.3f} px; right "
              f"camera at ({x:.2f}, {y:.2f}, {z:.2f}) mm in the left, baseline {diff['baseline_mm']:.2f} mm, "
              f"{diff['translation_mm']:.2f} mm and {diff['rotation_deg']:.3f} deg from CAD; epipolar error RMS "
              f"{epi['rms_px']:.3f} px, p99 {epi['p99_px']:.3f} px (at the CAD pose {epi_seed['rms_px']:.2f} px)")
        if check is not None:
            print(cross_check_line(check))
        for w in warnings:
            print(f"warning: {w}")
    if not epi["rms_px"] <= args.max_epipolar_rms:
        raise CheckFailed(f"{args.out}/stereo.json: epipolar error RMS {epi['rms_px']:.3f} px above "
                          f"--max-epipolar-rms {args.max_epipolar_rms:g} px: the pose or the mono models are wrong "
                          f"(try --refine-intrinsics, or recalibrate each camera)")
    return 0
