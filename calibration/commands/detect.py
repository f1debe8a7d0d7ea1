"""`calibrate detect`: find a calibration target's points (a checkerboard's corners, a marker
checkerboard's, a circle grid's centres) in thermal images through the same ``detect_target`` as
`calibrate thermal`; write corners.vnl (mrcal's corners cache) and detections.json."""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from platform_tools.rig import atomic
from platform_tools.rig.conventions import UserError, add_output_options, print_json

from calibration.formats.corners_vnl import BoardCorners, format_corners
from calibration.detect import ImageError, detect_files, list_images
from calibration.detect.batch import board_size_problem
from calibration.commands.synth import parse_board
from calibration.targets import TARGET_KINDS, TargetError


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "detect", help="detect a calibration target's corners or circle centres in thermal images (writes corners.vnl)",
        description="Find the W x H points of a calibration target in thermal images (16-bit raw counts or "
                    "8-bit; PNG, TIFF, PGM), with the same detector as `calibrate thermal --target`: a "
                    "checkerboard's inner corners (default), a marker checkerboard's (its marker's own 3x3 "
                    "corners are never reported), or a circle grid's disc centres (each disc's area centroid, "
                    "uncorrected: `calibrate thermal` takes the centroid's bias off in its solve, a corners file "
                    "cannot). Partial or occluded boards give the points seen, at their board coordinates, where "
                    "the target allows it. Writes DIR/corners.vnl (mrcal-calibrate-cameras --corners-cache "
                    "--object-width-n W --object-height-n H reads it; a lattice point with no disc, or a point "
                    "not seen, is '-') and DIR/detections.json (per image: points found, or why not). A "
                    "checkerboard's corner (0, 0) is its top-left corner as seen in the image (hold it less "
                    "than 45 deg from upright); a marker board labels its own corner (0, 0) at any roll; a "
                    "circle grid follows the rule in docs/calibration.md (\"Circle grids\").",
        epilog="Exit codes: 0 a board found in at least one image (corners.vnl and detections.json written); "
               "2 bad input (an unreadable or corrupt image, two images of one file name, a --board the --target "
               "cannot have, views showing a board larger than --board, no board found in any image), one line, "
               "nothing written.")
    p.add_argument("--images", required=True, metavar="DIR|GLOB", help="a folder of images or a quoted glob")
    p.add_argument("--board", required=True, metavar="WxH",
                   help="inner corners across x down, e.g. 10x7 (circle-grid: discs across x down; "
                        "asymmetric-circle-grid: the lattice, W twice the discs per row: OpenCV's (4, 11) is 8x11)")
    p.add_argument("--target", default="checkerboard", choices=TARGET_KINDS,
                   help="checkerboard (default), marker-checkerboard, circle-grid, asymmetric-circle-grid "
                        "(as calibrate thermal --target; docs/calibration.md)")
    p.add_argument("--out", required=True, metavar="DIR", type=Path, help="output folder (replaced whole)")
    p.add_argument("--weights", action="store_true",
                   help="write weights (2^-level) instead of levels: for --corners-cache-has-weights")
    add_output_options(p)
    p.set_defaults(handler=cmd_detect)


def cmd_detect(args: argparse.Namespace) -> int:
    W, H = parse_board(args.board)
    try:
        from calibration.detect.targets import check_target_board
        check_target_board(args.target, (W, H))
    except TargetError as exc:
        raise UserError(f"{exc}; nothing written") from None
    try:
        files = list_images(args.images)
        results = detect_files(files, (W, H), strict=True, show_progress=not args.quiet, target=args.target)
    except ImageError as exc:
        raise UserError(f"{exc}; nothing written") from None
    why = board_size_problem(results, (W, H))
    if why:
        raise UserError(f"{args.images}: {why}; nothing written")
    names = [r.path.name for r in results]
    if len(set(names)) != len(names):
        raise UserError(f"{args.images}: two images share a file name; the corners file names images by "
                        f"file name, so give one folder at a time")
    sizes = {r.imagersize for r in results}
    rows, summary = [], []
    for r in results:
        d = r.detection
        rows.append(BoardCorners(r.path.name, d.corners if d.detected else None, d.level if d.detected else None))
        summary.append({"file": r.path.name, "found": d.found, "complete": d.complete,
                        "reason": d.reason, "imagersize": list(r.imagersize)})
    n_det = sum(1 for s in summary if s["found"])
    n_full = sum(1 for s in summary if s["complete"])
    report = {"images": len(results), "detected": n_det, "complete": n_full, "board": [W, H], "target": args.target,
              "imagersize": [list(s) for s in sorted(sizes)], "out": str(args.out), "per_image": summary}
    if n_det == 0:
        reasons = sorted({s["reason"] for s in summary if s["reason"]})
        raise UserError(f"{args.images}: no {W}x{H} {args.target} found in any of {len(results)} images "
                        f"({'; '.join(reasons[:2])}); check --board and --target and the image contrast; "
                        f"nothing written")
    with atomic.OutputDir(args.out) as stage:
        (stage / "corners.vnl").write_text(format_corners(rows, weights=args.weights))
        (stage / "detections.json").write_text(json.dumps(report, indent=1))
    if args.json:
        print_json(report)
    elif not args.quiet:
        print(f"{args.out / 'corners.vnl'}: {args.target} {W}x{H} found in {n_det} of {len(results)} images "
              f"({n_full} complete, {n_det - n_full} partial)")
        for s in summary:
            if not s["found"] and args.verbose:
                print(f"  {s['file']}: {s['reason']}")
    return 0
