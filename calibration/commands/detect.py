"""`calibrate detect`: find heated-checkerboard corners in thermal images; write corners.vnl."""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from platform_tools.rig import atomic
from platform_tools.rig.conventions import UserError, add_output_options, print_json

from calibration.formats.corners_vnl import BoardCorners, format_corners
from calibration.detect import ImageError, detect_files, list_images
from calibration.commands.synth import parse_board


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "detect", help="detect heated-checkerboard corners in thermal images (writes corners.vnl)",
        description="Find the W x H inner corners of a checkerboard in thermal images (16-bit raw counts "
                    "or 8-bit; PNG, TIFF, PGM). Boards partly outside the image or occluded give the corners "
                    "seen, at their board coordinates. Writes DIR/corners.vnl (mrcal-calibrate-cameras "
                    "--corners-cache reads it) and DIR/detections.json (per image: corners found, or why "
                    "not). Corner (0, 0) is the board's top-left corner as seen in the image; hold the "
                    "board less than 45 deg from upright so that every image agrees.")
    p.add_argument("--images", required=True, metavar="DIR|GLOB", help="a folder of images or a quoted glob")
    p.add_argument("--board", required=True, metavar="WxH", help="inner corners across x down, e.g. 10x7")
    p.add_argument("--out", required=True, metavar="DIR", type=Path, help="output folder (replaced whole)")
    p.add_argument("--weights", action="store_true",
                   help="write weights (2^-level) instead of levels: for --corners-cache-has-weights")
    add_output_options(p)
    p.set_defaults(handler=cmd_detect)


def cmd_detect(args: argparse.Namespace) -> int:
    W, H = parse_board(args.board)
    try:
        files = list_images(args.images)
        results = detect_files(files, (W, H), strict=True, show_progress=not args.quiet)
    except ImageError as exc:
        raise UserError(f"{exc}; nothing written") from None
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
    report = {"images": len(results), "detected": n_det, "complete": n_full, "board": [W, H],
              "imagersize": [list(s) for s in sorted(sizes)], "out": str(args.out), "per_image": summary}
    if n_det == 0:
        reasons = sorted({s["reason"] for s in summary if s["reason"]})
        raise UserError(f"{args.images}: no {W}x{H} board found in any of {len(results)} images "
                        f"({'; '.join(reasons[:2])}); check --board (inner corners across x down) and the "
                        f"image contrast; nothing written")
    with atomic.OutputDir(args.out) as stage:
        (stage / "corners.vnl").write_text(format_corners(rows, weights=args.weights))
        (stage / "detections.json").write_text(json.dumps(report, indent=1))
    if args.json:
        print_json(report)
    elif not args.quiet:
        print(f"{args.out / 'corners.vnl'}: board {W}x{H} found in {n_det} of {len(results)} images "
              f"({n_full} complete, {n_det - n_full} partial)")
        for s in summary:
            if not s["found"] and args.verbose:
                print(f"  {s['file']}: {s['reason']}")
    return 0
