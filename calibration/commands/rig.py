"""`calibrate rig`: refine the rig's extrinsics (and the thermal pair's intrinsics) from synchronised
images of a board seen by the ZED X and both thermal cameras, seeded from the CAD model; report how
far the built rig is from its design (docs/extrinsics.md)."""
from __future__ import annotations

import argparse
import json
import logging
from pathlib import Path

import numpy as np

from platform_tools.rig import atomic
from platform_tools.rig.conventions import (CheckFailed, UserError, add_output_options, add_rig_options,
    print_json, rig_from_args)

from calibration.commands.synth import parse_board

log = logging.getLogger("calibration.rig")
DEPTHS_M = (1.5, 5.0)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "rig", help="refine every camera's extrinsics (and thermal intrinsics) from synchronised board images",
        description="Detect the board in synchronised sets (DIR/zed_left, zed_right, thermal_left, thermal_right: "
                    "one image per camera per set, paired by timestamp names or equal names), solve the thermal "
                    "pair's intrinsics and all extrinsics jointly with mrcal from the CAD poses, and report each "
                    "camera's difference from CAD (mm, deg) and the RGB-to-thermal reprojection error at 1.5 m "
                    "and 5 m. Writes --out: extrinsics.yaml, kalibr_camchain.yaml, rig.urdf, "
                    "static_transforms.launch.xml, one .cameramodel per camera, report.json.",
        epilog="Exit codes: 0 solved (a camera beyond the tolerance is a warning), 1 not solvable, 2 bad input.")
    p.add_argument("--images", required=True, type=Path, metavar="DIR", help="folder with one sub-folder per camera")
    p.add_argument("--board", default="10x7", metavar="WxH", help="inner corners across x down (default 10x7)")
    p.add_argument("--square", type=float, default=0.05, metavar="METRES", help="square size in metres (default 0.05)")
    p.add_argument("--out", type=Path, default=Path("build/calibration/rig"), metavar="DIR",
                   help="output folder, replaced whole (default build/calibration/rig)")
    p.add_argument("--zed-models", type=Path, metavar="DIR", default=None,
                   help="folder with zed_left.cameramodel and zed_right.cameramodel (e.g. from the ZED's factory "
                        "calibration); default: the rig's nominal ZED pinhole, scaled to the images' size")
    p.add_argument("--zed-intrinsics", choices=("fixed", "solved"), default="fixed",
                   help="hold the ZED lens at the given/nominal models (default; its images are rectified) or "
                        "solve it too")
    p.add_argument("--tolerance-mm", type=float, default=5.0, help="warn when a camera is further than this "
                                                                    "from its CAD pose (default 5 mm)")
    p.add_argument("--tolerance-deg", type=float, default=1.0, help="warn when a camera is turned more than this "
                                                                     "from its CAD pose (default 1 deg)")
    p.add_argument("--pair-tolerance-ms", type=float, default=None,
                   help="timestamp pairing tolerance (default: the rig's processing.pair_tolerance_ms)")
    add_rig_options(p)
    add_output_options(p)
    p.set_defaults(handler=cmd_rig)


def _zed_seed(rig, short: str, size: tuple[int, int], models: Path | None):
    from calibration.extrinsics.outputs import CameraIntrinsics, nominal_lenses
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
        lm, intr = m.intrinsics()
        if tuple(int(x) for x in m.imagersize()) != tuple(size):
            raise UserError(f"{path}: the model is {m.imagersize()[0]}x{m.imagersize()[1]}, the {short} images are "
                            f"{size[0]}x{size[1]}")
        return CameraIntrinsics(lm, np.asarray(intr, float), tuple(size))
    nom = nominal_lenses(rig)[short]
    W, H = nom.imagersize
    s = size[0] / W
    if abs(size[1] - H * s) > 1.0:
        raise UserError(f"{short}/ images are {size[0]}x{size[1]}, not the rig's {W}x{H} ZED at any scale; "
                        f"give --zed-models")
    from calibration.rigsynth.render import scaled_pinhole
    f, _, cx, cy = nom.intrinsics
    lens = scaled_pinhole(f, W, H, s)
    if abs(cx - (W - 1) / 2) > 1e-9 or abs(cy - (H - 1) / 2) > 1e-9:
        raise UserError("the nominal ZED model is not centred; give --zed-models")
    return CameraIntrinsics(lens.lensmodel, np.array(lens.intrinsics), tuple(size))


def _thermal_seed(rig, short: str, size: tuple[int, int]):
    from calibration.extrinsics.outputs import CameraIntrinsics
    from calibration.synth.lens import nominal_thermal_lens
    lens = nominal_thermal_lens(rig, short)
    if tuple(lens.imagersize) != tuple(size):
        raise UserError(f"{short}/ images are {size[0]}x{size[1]}; the rig's thermal camera is "
                        f"{lens.imagersize[0]}x{lens.imagersize[1]}")
    return CameraIntrinsics(lens.lensmodel, lens.intrinsics_array, tuple(size))


def reprojection(cad, sol, halves=None) -> dict:
    """Per thermal camera and depth: where a ZED left pixel's point lands in the thermal image through
    the CAD extrinsics against through the refined ones (px), and the refined extrinsics' own error,
    estimated by cross-validation (two solves on the even and the odd sets: half the difference of their
    extrinsics, both through the full solve's lenses)."""
    from calibration.extrinsics.cad import CAMERAS
    from calibration.extrinsics.solve import mapping_error_px, rgb_to_thermal_px
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


def cmd_rig(args: argparse.Namespace) -> int:
    from calibration.extrinsics.cad import CAMERAS
    from calibration.extrinsics.outputs import all_files, cameramodel_text, pose_dict
    from calibration.extrinsics.sets import SetError, detect_sets, find_sets, usable
    from calibration.extrinsics.solve import RigSolveError, difference, refined_tree, solve_rig
    from calibration.commands.extrinsics import frames_or_user_error

    rig = rig_from_args(args)
    board = parse_board(args.board)
    if not 0.001 <= args.square <= 1.0:
        raise UserError(f"--square {args.square}: expected the square size in metres, 0.001 to 1")
    for name in ("tolerance_mm", "tolerance_deg"):
        if not getattr(args, name) > 0:
            raise UserError(f"--{name.replace('_', '-')} {getattr(args, name)}: must be > 0")
    tol_ms = args.pair_tolerance_ms if args.pair_tolerance_ms is not None else \
        float(rig.desc.processing.pair_tolerance_ms)
    if not tol_ms > 0:
        raise UserError(f"--pair-tolerance-ms {tol_ms}: must be > 0")
    cad = frames_or_user_error(rig)
    try:
        sets = find_sets(args.images, tol_ms)
        obs = usable(detect_sets(sets, board, args.square, show_progress=not args.quiet))
    except SetError as exc:
        raise UserError(str(exc)) from None
    seeds = {c: (_zed_seed(rig, c, obs.imagersizes[c], args.zed_models) if c.startswith("zed") else
                 _thermal_seed(rig, c, obs.imagersizes[c])) for c in CAMERAS}
    try:
        sol = solve_rig(obs, seeds, cad, zed_intrinsics=args.zed_intrinsics)
        halves = None
        if obs.n >= 8:
            idx = np.arange(obs.n)
            halves = [solve_rig(obs.subset(idx % 2 == k), seeds, cad, zed_intrinsics=args.zed_intrinsics)
                      for k in (0, 1)]
    except RigSolveError as exc:
        raise CheckFailed(str(exc)) from None
    except Exception as exc:   # mrcal reports a singular problem as a bare exception
        if "mrcal" not in type(exc).__module__ and not isinstance(exc, (ValueError, np.linalg.LinAlgError)):
            raise
        raise CheckFailed(f"the joint solve failed ({str(exc).splitlines()[0][:160]}); more sets, or boards "
                          f"nearer the cameras") from None
    tree = refined_tree(cad, sol)
    diffs, warnings = {}, []
    for c, frame in CAMERAS.items():
        mm, deg, D = difference(cad.T_rig[frame], tree.T_rig[frame])
        dr = tree.T_rig[frame].t - cad.T_rig[frame].t
        diffs[c] = {"mm": mm, "deg": deg, "rig_axes_mm": [float(x) for x in dr],
                    "in_camera_frame": pose_dict(D), "anchor": c == "zed_left"}
        if mm > args.tolerance_mm or deg > args.tolerance_deg:
            warnings.append(f"{c} is {mm:.2f} mm and {deg:.3f} deg from its CAD pose (tolerance {args.tolerance_mm:g} "
                            f"mm, {args.tolerance_deg:g} deg): check how it is mounted")
    reproj = reprojection(cad, sol, halves)
    report = {
        "images": str(args.images), "sets": len(sets), "sets_used": obs.n, "sets_dropped": obs.dropped,
        "board": {"width": board[0], "height": board[1], "square_m": args.square},
        "zed_intrinsics": args.zed_intrinsics, "anchor": "zed_left (its CAD pose defines the rig frame)",
        "rms_px": sol.rms_px, "observations": sol.n_obs, "outlier_corners": sol.n_outliers,
        "difference_from_cad": diffs, "tolerance": {"mm": args.tolerance_mm, "deg": args.tolerance_deg},
        "warnings": warnings, "rgb_to_thermal_reprojection": reproj,
        "intrinsics": {c: {"lensmodel": l.lensmodel, "intrinsics": [float(x) for x in l.intrinsics],
                           "imagersize": list(l.imagersize)} for c, l in sol.lenses.items()}}
    models = {}
    for k, c in enumerate(CAMERAS):
        models[c] = cameramodel_text(tree, c, sol.lenses[c], f"{c}, refined by `calibrate rig` from {args.images}; "
                                     f"extrinsics rt_fromref: rig frame -> optical frame, metres",
                                     optimization_inputs={"inputs": sol.inputs, "icam": k})
    files = all_files(tree, sol.lenses, rig, source=f"refined from {obs.n} synchronised sets, seeded from CAD",
                      extra={"difference_from_cad": {c: {"mm": round(d["mm"], 4), "deg": round(d["deg"], 5)}
                                                     for c, d in diffs.items()}}, models=models)
    files["report.json"] = json.dumps(report, indent=1, default=float) + "\n"
    with atomic.OutputDir(args.out) as stage:
        for name, text in files.items():
            (stage / name).write_text(text)
    for w in warnings:
        log.warning(w)
    if args.json:
        print_json(dict(report, out=str(args.out), files=sorted(files)))
    elif not args.quiet:
        print(f"{args.out}: {obs.n} sets, RMS " + ", ".join(f"{c} {v:.3f}" for c, v in sol.rms_px.items()) + " px")
        print("difference from CAD (the ZED left camera is the anchor):")
        for c, d in diffs.items():
            if not d["anchor"]:
                print(f"  {c:14s} {d['mm']:7.3f} mm {d['deg']:7.4f} deg" + ("  WARNING" if d['mm'] > args.tolerance_mm
                                                                         or d['deg'] > args.tolerance_deg else ""))
        print("RGB (ZED left) to thermal reprojection, RMS px: CAD vs refined [refined, cross-validated]:")
        for th, rows in reproj.items():
            print(f"  {th:14s} " + "  ".join(
                f"{k}: {r['cad_vs_refined']['rms_px']:.2f}" + (f" [{r['refined_cross_validation']['rms_px']:.3f}]"
                                                             if "refined_cross_validation" in r else "")
                for k, r in rows.items()))
    return 0
