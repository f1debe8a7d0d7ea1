"""`calibrate synth`: synthetic thermal images of a heated checkerboard with exact ground truth."""
from __future__ import annotations

import argparse
import re
from pathlib import Path

from platform_tools.rig.conventions import (UserError, add_output_options, add_rig_options, print_json,
    rig_from_args)

from calibration.synth import DIFFICULTIES, render_dataset
from calibration.synth.lens import nominal_thermal_lens
from calibration.synth.truth_families import FAMILIES, truth_lens


def parse_board(text: str) -> tuple[int, int]:
    """'10x7' -> (10, 7): inner corners across x down, as OpenCV's pattern size."""
    m = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", text or "")
    if not m:
        raise UserError(f"--board {text!r}: expected WxH in inner corners, e.g. 10x7")
    w, h = int(m.group(1)), int(m.group(2))
    if w < 2 or h < 2 or w > 100 or h > 100:
        raise UserError(f"--board {text!r}: each side needs 2 to 100 inner corners")
    return w, h


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "synth", help="render synthetic thermal images of a heated checkerboard, with ground truth",
        description="Render 640x512 16-bit thermal images of a heated checkerboard through a known fisheye "
                    "lens (LENSMODEL_OPENCV8 close to the rig's nominal Boson 4.9 mm / 95 deg), with "
                    "microbolometer effects. Writes DIR/NNN.png, DIR/truth.cameramodel and DIR/truth.json "
                    "(every board pose and the true pixel position of every corner). "
                    "See docs/calibration-synthetic.md.")
    p.add_argument("--out", metavar="DIR", required=True, type=Path, help="output folder (replaced whole)")
    p.add_argument("--n", type=int, default=40, help="number of images (default 40)")
    p.add_argument("--difficulty", choices=DIFFICULTIES, default="real",
                   help="easy: clean, central boards; real: what a careful user records; hard: low contrast, "
                        "heavy noise, steep tilts, clutter, occlusions (default real)")
    p.add_argument("--board", default="10x7", help="inner corners across x down (default 10x7)")
    p.add_argument("--square", type=float, default=0.04, help="square size in metres (default 0.04)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0): same seed, same images")
    p.add_argument("--camera", default="thermal_left", help="camera of the rig whose nominal lens is used "
                                                            "(default thermal_left)")
    p.add_argument("--truth-lens", choices=FAMILIES, default="opencv8",
                   help="family of the truth lens (default opencv8, the rig's nominal lens); the others are "
                        "rendered in closed form and write their own truth files (docs/calibration-synthetic.md)")
    p.add_argument("--output", choices=("y16", "agc8"), default="y16",
                   help="y16: 16-bit counts (default); agc8: 8-bit histogram-equalised, as a Boson in 8-bit mode")
    add_rig_options(p)
    add_output_options(p)
    p.set_defaults(handler=cmd_synth)


def cmd_synth(args: argparse.Namespace) -> int:
    board = parse_board(args.board)
    if not 1 <= args.n <= 100000:
        raise UserError(f"--n {args.n}: render between 1 and 100000 images")
    if not (0.001 <= args.square <= 1.0):
        raise UserError(f"--square {args.square}: the square size is in metres, between 0.001 and 1")
    rig = rig_from_args(args)
    try:
        lens = nominal_thermal_lens(rig, args.camera)
        if args.truth_lens != "opencv8":
            lens = truth_lens(args.truth_lens, lens.imagersize(), rig)
    except KeyError as exc:
        raise UserError(f"--camera {args.camera}: {exc.args[0]}") from None
    except ValueError as exc:
        raise UserError(f"rig description: {exc}") from None
    try:
        truth = render_dataset(args.out, n=args.n, difficulty=args.difficulty, board=board, square=args.square,
                               seed=args.seed, lens=lens, show_progress=not args.quiet,
                               output=args.output)
    except RuntimeError as exc:
        raise UserError(str(exc)) from None
    summary = {"out": str(args.out), "images": len(truth["images"]), "difficulty": args.difficulty,
               "board": truth["board"], "seed": args.seed, "lensmodel": truth["lensmodel"],
               "intrinsics": truth["intrinsics"],
               "fully_visible": sum(1 for im in truth["images"] if im["visible"] == board[0] * board[1]),
               "partial": sum(1 for im in truth["images"] if im["visible"] < board[0] * board[1]),
               "occluded": sum(1 for im in truth["images"] if im["occluded"])}
    if args.json:
        print_json(summary)
    elif not args.quiet:
        print(f"{args.out}: {summary['images']} {args.difficulty} images ({summary['fully_visible']} boards fully "
              f"visible, {summary['partial']} partly outside, {summary['occluded']} occluded), truth.json, "
              f"{', '.join(truth.get('truth_lens', {}).get('files', ['truth.cameramodel']))}")
    return 0
