"""`calibrate rig`: refine the rig's extrinsics (and the thermal pair's intrinsics) from synchronised
images of a board seen by the ZED X and both thermal cameras, seeded from the CAD model; report how
far the built rig is from its design (docs/extrinsics.md). Parses and prints; the work is in
calibration/extrinsics/refine.py."""
from __future__ import annotations

import argparse
import json
import logging
from pathlib import Path

from platform_tools.rig import atomic
from platform_tools.rig.conventions import (UserError, add_output_options, add_rig_options, print_json,
                                            rig_from_args)

from calibration.commands.synth import parse_board

log = logging.getLogger("calibration.rig")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "rig", help="refine every camera's extrinsics (and thermal intrinsics) from synchronised board images",
        description="Detect the board in synchronised sets (DIR/zed_left, zed_right, thermal_left, thermal_right: "
                    "one image per camera per set, paired by timestamp names or equal names), solve the thermal "
                    "pair's intrinsics and all extrinsics jointly with mrcal from the CAD poses, and report each "
                    "camera's difference from CAD (mm, deg) and the RGB-to-thermal reprojection error at 1.5 m "
                    "and 5 m. Writes --out: extrinsics.yaml, kalibr_camchain.yaml, rig.urdf, "
                    "static_transforms.launch.xml, pose_uncertainty.yaml (the prior), one .cameramodel per camera, "
                    "report.json. Each thermal camera's extrinsics are refined under a prior about its CAD pose whose "
                    "sigmas are the CAD model's tolerance stack-up (--prior).",
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
    p.add_argument("--prior", choices=("stack-up", "none"), default="stack-up",
                   help="the prior on each thermal camera's extrinsics about its CAD pose: the CAD model's tolerance "
                        "stack-up (default; its sigmas follow the fits and the printer tolerance of the rig, "
                        "written to pose_uncertainty.yaml) or none")
    p.add_argument("--pair-tolerance-ms", type=float, default=None,
                   help="timestamp pairing tolerance (default: the rig's processing.pair_tolerance_ms)")
    add_rig_options(p)
    add_output_options(p)
    p.set_defaults(handler=cmd_rig)


def cmd_rig(args: argparse.Namespace) -> int:
    import numpy as np

    from calibration.extrinsics.cad import CAMERAS
    from calibration.extrinsics.outputs import all_files, cameramodel_text
    from calibration.extrinsics.prior import stack_up_priors
    from calibration.extrinsics.refine import (differences_from_cad, prior_distance, reprojection, seeds,
                                               solve_with_halves)
    from calibration.extrinsics.sets import SetError, detect_sets, find_sets, usable
    from calibration.extrinsics.solve import refined_tree
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
    priors = stack_up_priors(rig) if args.prior == "stack-up" else {}
    sol, halves = solve_with_halves(obs, seeds(rig, obs, args.zed_models), cad, zed_intrinsics=args.zed_intrinsics,
                                    prior={c: p.covariance_optical for c, p in priors.items()})
    tree = refined_tree(cad, sol)
    diffs, warnings = differences_from_cad(cad, tree, tolerance_mm=args.tolerance_mm,
                                           tolerance_deg=args.tolerance_deg)
    sigmas, prior_warnings = prior_distance(cad, tree, priors)
    warnings += prior_warnings
    reproj = reprojection(cad, sol, halves)
    report = {
        "images": str(args.images), "sets": len(sets), "sets_used": obs.n, "sets_dropped": obs.dropped,
        "board": {"width": board[0], "height": board[1], "square_m": args.square},
        "zed_intrinsics": args.zed_intrinsics, "anchor": "zed_left (its CAD pose defines the rig frame)",
        "rms_px": sol.rms_px, "observations": sol.n_obs, "outlier_corners": sol.n_outliers,
        "difference_from_cad": diffs, "tolerance": {"mm": args.tolerance_mm, "deg": args.tolerance_deg},
        "warnings": warnings, "rgb_to_thermal_reprojection": reproj,
        "prior": {"source": "the CAD tolerance stack-up (pose_uncertainty.yaml)" if priors else "none",
                  "sigmas_from_cad": {c: round(v, 3) for c, v in sigmas.items()},
                  "sigma_optical_mm_deg": {c: [round(float(v), 5) for v in p.sigma_optical[:3]]
                                           + [round(float(v), 5) for v in np.degrees(p.sigma_optical[3:])]
                                           for c, p in priors.items()}},
        "intrinsics": {c: {"lensmodel": l.intrinsics()[0], "intrinsics": [float(x) for x in l.intrinsics()[1]],
                           "imagersize": [int(x) for x in l.imagersize()]} for c, l in sol.lenses.items()}}
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
