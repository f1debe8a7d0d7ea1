"""What biases thermal intrinsics: each effect of the synthetic thermal images alone, measured as the
error it puts into the solved lens through each detector's corner errors, side by side for our
detector, OpenCV's findChessboardCornersSB and mrgingham, on the same images.

    .venv/bin/python bench/bench_corner_bias.py [--n 40] [--seed 7] [--work build/bench_corner_bias] [--reuse] [--json]

The "real" difficulty (square 8x8 board, so that mrgingham runs too) is rendered several times with
the same board poses and optics: "clean" (no noise, no sensor or scene effects; optical blur and heat
spreading stay), then clean plus ONE effect, then everything ("real"). For each set and detector:
corners found within 1 px of the truth, their RMS error, and what those errors do to the lens: the
first-order change of the intrinsics when the mrcal problem that sits exactly at the truth (the true
corners the detector found, unregularised OPENCV8, board warp free: calibrate thermal's final solve)
gets the detector's corners instead (calibration.intrinsics.sensitivity), and the projection
difference that makes over the image (whole / central 80%, after the best-fit rotation, as
calibrate validate reports it; first order too). Nothing is re-solved, so mrcal's outlier rejection cannot hide or
add a bias by chance.

Read it as: a systematic effect (the same sign whatever the noise) is a bias no number of images
removes; the temporal noise row is one draw of a random spread (about +-0.03 px in focal length for 40
images at "real" noise). OpenCV and mrgingham get 8-bit images (0.5-99.5 percentile stretch), as they
need; ours reads the 16-bit counts. Corners more than 1 px off are left out for every detector.
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import os
import sys
import time
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
os.environ.setdefault("OMP_NUM_THREADS", "1")
cv2.setNumThreads(1)

from calibration.detect import detect_corners  # noqa: E402
from calibration.intrinsics.sensitivity import parameter_shift, problem_at_truth, projection_shift  # noqa: E402
from calibration.synth import render_dataset  # noqa: E402
from calibration.synth.difficulty import level  # noqa: E402
from calibration.lens.compare import central_mask  # noqa: E402

import bench_detection  # noqa: E402  (its 8-bit conversion and the reference tools' runs)

BOARD = (8, 8)
SQUARE = 0.04
OFF = dict(noise_k=0.0, column_fpn_k=0.0, gain_nonuniformity=0.0, vignette=0.0, housing_k=0.0,
           board_gradient=0.0, reflection_prob=0.0, clutter=0)
# (set name, what is switched back on from "real" over the clean set; None: everything)
EFFECTS = [
    ("clean", {}),
    ("+ temporal noise", dict(noise_k=None)),
    ("+ column pattern", dict(column_fpn_k=None)),
    ("+ vignetting, gain, warm housing", dict(vignette=None, gain_nonuniformity=None, housing_k=None)),
    ("+ board rim falloff", dict(board_gradient=None)),
    ("+ warm reflection", dict(reflection_prob=None)),
    ("+ background clutter", dict(clutter=None)),
    ("real (all of them)", None),
]
MAX_ERR_PX = 1.0


def difficulty(on: dict | None, name: str):
    real = level("real")
    if on is None:
        return real
    kw = {k: v for k, v in OFF.items() if k not in on}
    return dataclasses.replace(real, name=name, **kw)


def square_symmetries(c: np.ndarray, w: int, h: int):
    """The grid orderings a detector without our orientation convention may return: 180 deg always,
    and the 90 deg turns and mirrors too when the board is square."""
    g = c.reshape(h, w, 2)
    outs = [g, g[::-1, ::-1]]
    if w == h:
        outs += [np.rot90(g, k) for k in (1, 3)] + [g[::-1], g[:, ::-1], g.transpose(1, 0, 2),
                                                     g[::-1, ::-1].transpose(1, 0, 2)]
    return [o.reshape(-1, 2) for o in outs]


def aligned(pred: np.ndarray, truth: np.ndarray) -> np.ndarray:
    best, score = None, np.inf
    for p in square_symmetries(pred, *BOARD):
        with np.errstate(invalid="ignore"):
            s = np.nanmedian(np.linalg.norm(p - truth, axis=1))
        if s < score:
            best, score = p, s
    return best if best is not None else np.full_like(pred, np.nan)


def run_ours(folder: Path, files: list[str]) -> dict:
    return {f: detect_corners(cv2.imread(str(folder / f), cv2.IMREAD_UNCHANGED), BOARD).corners for f in files}


def run_opencv(folder: Path, files: list[str]) -> dict:
    return bench_detection.run_opencv(folder, files, BOARD)[0]


def run_mrgingham(folder: Path, files: list[str]) -> dict:
    return bench_detection.run_mrgingham(folder, files, BOARD, folder.parent)[0]


DETECTORS = [("ours", run_ours), ("OpenCV SB", run_opencv), ("mrgingham", run_mrgingham)]


def effect_of(truth: dict, found: dict) -> dict:
    """Corner errors of one detector on one set, and what they do to the lens."""
    n_c = BOARD[0] * BOARD[1]
    rts, tq, err = [], [], []
    for im in truth["images"]:
        q = np.array([c if c is not None else [np.nan, np.nan] for c in im["corners"]], float)
        c = found.get(im["file"])
        if c is None or not np.isfinite(c).any():
            continue
        c = aligned(np.asarray(c, float).reshape(n_c, 2), q)
        with np.errstate(invalid="ignore"):
            e = c - q
            good = np.isfinite(e).all(axis=1) & (np.linalg.norm(e, axis=1) <= MAX_ERR_PX)
        if good.sum() < 8:
            continue
        rts.append(im["rt_cam_board"])
        tq.append(np.where(good[:, None], q, np.nan))
        err.append(np.where(good[:, None], e, np.nan))
    if len(rts) < 4:
        return dict(images=len(rts), corners=0)
    lm, intr = truth["lensmodel"], np.array(truth["intrinsics"])
    size = tuple(truth["imagersize"])
    oi = problem_at_truth(lm, intr, np.array(rts), np.array(tq), BOARD, SQUARE, size)
    d = parameter_shift(oi, np.array(err))["intrinsics"]
    grid, diff = projection_shift(lm, intr, d, size)
    central = central_mask(grid, size)
    e = np.concatenate(err)
    e = e[np.isfinite(e[:, 0])]
    return dict(images=len(rts), corners=int(len(e)), rms_px=float(np.sqrt((e ** 2).sum(1).mean())),
                d_fx=float(d[0]), d_fy=float(d[1]), d_cx=float(d[2]), d_cy=float(d[3]),
                proj_rms_px=float(np.sqrt(np.nanmean(diff ** 2))),
                proj_central_px=float(np.sqrt(np.nanmean(diff[central] ** 2))))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=40)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--work", type=Path, default=Path("build/bench_corner_bias"))
    ap.add_argument("--reuse", action="store_true",
                    help="reuse the sets already rendered in --work (same --n and --seed) instead of rendering")
    ap.add_argument("--json", action="store_true", help="print one JSON document instead of the table")
    args = ap.parse_args()
    rows = []
    t0 = time.perf_counter()
    for k, (name, on) in enumerate(EFFECTS):
        folder = args.work / f"set{k}"
        old = folder / "truth.json"
        truth = json.loads(old.read_text()) if args.reuse and old.exists() else None
        if truth is None or len(truth["images"]) != args.n or truth["seed"] != args.seed:
            truth = render_dataset(folder, n=args.n, difficulty=difficulty(on, f"real-{k}"), board=BOARD,
                                   square=SQUARE, seed=args.seed, show_progress=False)
        files = [im["file"] for im in truth["images"]]
        for det, fn in DETECTORS:
            r = effect_of(truth, fn(folder, files))
            rows.append(dict(effect=name, detector=det, **r))
            if not args.json:
                print(f"  {name}: {det} done ({time.perf_counter() - t0:.0f} s)", file=sys.stderr, flush=True)
    if args.json:
        print(json.dumps(dict(n=args.n, seed=args.seed, board=list(BOARD), rows=rows), indent=1))
        return 0
    print(f"\nreal set, {args.n} images, board {BOARD[0]}x{BOARD[1]}, seed {args.seed}: the lens error each "
          f"effect causes through each detector's corners (first order, no outlier rejection)\n")
    print(f"{'effect':34s} {'detector':10s} {'corners':>7s} {'RMS px':>7s} {'d fx':>7s} {'d fy':>7s} "
          f"{'d cx':>7s} {'d cy':>7s} {'proj RMS':>8s} {'central':>7s}")
    for r in rows:
        if not r.get("corners"):
            print(f"{r['effect']:34s} {r['detector']:10s} {'too few boards':>7s}")
            continue
        print(f"{r['effect']:34s} {r['detector']:10s} {r['corners']:7d} {r['rms_px']:7.4f} {r['d_fx']:+7.3f} "
              f"{r['d_fy']:+7.3f} {r['d_cx']:+7.3f} {r['d_cy']:+7.3f} {r['proj_rms_px']:8.4f} "
              f"{r['proj_central_px']:7.4f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
