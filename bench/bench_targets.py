"""Benchmark: --target marker-checkerboard, ours beside OpenCV's findChessboardCornersSB, on the same
synthetic images through four truth lens families.

    .venv/bin/python bench/bench_targets.py [--n 10] [--seed 40] [--json FILE]

Per truth lens (opencv8, kannala-brandt, stereographic, boson-published) and difficulty (real, hard):
n views of a 10x7 marker checkerboard (calibration/targets/spec.py) drawn as calibrate synth draws
board poses (partial views over the image's edges and corners included), rendered by
calibration/synth/targets_render.py. Columns: views with the marker and the squares around it in
view; of those, the share ours labels; views with every non-marker corner in view and ours
complete; corners reported, corner RMS against the truth (px), corners more than 1 px from their
own truth (wild corners or wrong labels: must be 0), marker corners reported (must be 0); the plain
checkerboard detector on the same images (views it labels); OpenCV SB: views where it finds the
whole 10x7 grid (the marker's hole breaks it) and its RMS on them (best of the two 180 deg
orderings); ms per image for ours and for SB (median, one core) and their ratio. OpenCV gets 8-bit
images (0.5-99.5 percentile stretch); ours reads the 16-bit counts.
"""
from __future__ import annotations

import argparse
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

from calibration.detect import detect_corners, detect_marker_board  # noqa: E402
from calibration.synth.targets_render import MarkerBoard, render_views  # noqa: E402
from calibration.synth.truth_families import FAMILIES, truth_lens  # noqa: E402
from calibration.targets import marker_block  # noqa: E402

BOARD = (10, 7)


def to8(img):
    lo, hi = np.percentile(img, [0.5, 99.5])
    return np.clip((img.astype(np.float32) - lo) / max(hi - lo, 1) * 255, 0, 255).astype(np.uint8)


def run_set(family: str, difficulty: str, n: int, seed: int) -> dict:
    W, H = BOARD
    block = marker_block(BOARD)
    around = np.zeros((H, W), bool)
    around[1:6, 2:7] = True
    views = render_views(truth_lens(family), MarkerBoard(W, H, 0.04), difficulty, n=n, seed=seed)
    r = dict(family=family, difficulty=difficulty, n=n, readable=0, labelled_readable=0, whole=0, complete=0,
             corners=0, wild=0, marker_reported=0, plain_labelled=0, sb_found=0)
    errs, sb_errs, t_ours, t_sb = [], [], [], []
    for img, q, occ in views:
        t0 = time.perf_counter()
        det = detect_marker_board(img, BOARD)
        t_ours.append(time.perf_counter() - t0)
        rep = np.isfinite(det.corners[:, 0])
        e = np.linalg.norm(det.corners[rep] - q[rep], axis=1)
        e = np.where(np.isfinite(e), e, np.inf)          # reported where the truth is out of view
        readable = bool(np.isfinite(q[around.ravel(), 0]).all()) and not occ.any()
        r["readable"] += readable
        r["labelled_readable"] += readable and det.detected
        whole = bool(np.isfinite(q[~block, 0]).all())
        r["whole"] += whole
        r["complete"] += whole and det.found == int((~block).sum())
        r["corners"] += int(rep.sum())
        r["wild"] += int(np.sum(e > 1.0))
        r["marker_reported"] += int(np.sum(rep & block))
        errs.extend(e[np.isfinite(e)].tolist())
        r["plain_labelled"] += detect_corners(img, BOARD).detected
        t0 = time.perf_counter()
        ok, c = cv2.findChessboardCornersSB(to8(img), BOARD, flags=cv2.CALIB_CB_NORMALIZE_IMAGE)
        t_sb.append(time.perf_counter() - t0)
        if ok and np.isfinite(q[:, 0]).all():
            c = c.reshape(-1, 2)
            d = min(np.linalg.norm(c - q, axis=1).tolist(), np.linalg.norm(c[::-1] - q, axis=1).tolist(),
                    key=lambda x: float(np.mean(np.square(x))))
            r["sb_found"] += 1
            sb_errs.extend(d)
    r["rms_px"] = float(np.sqrt(np.mean(np.square(errs)))) if errs else None
    r["sb_rms_px"] = float(np.sqrt(np.mean(np.square(sb_errs)))) if sb_errs else None
    r["ms_ours"], r["ms_sb"] = 1e3 * float(np.median(t_ours)), 1e3 * float(np.median(t_sb))
    r["time_ratio_ours_over_sb"] = r["ms_ours"] / max(r["ms_sb"], 1e-9)
    return r


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=10)
    ap.add_argument("--seed", type=int, default=40)
    ap.add_argument("--families", default=",".join(FAMILIES))
    ap.add_argument("--difficulties", default="real,hard")
    ap.add_argument("--json", type=Path)
    a = ap.parse_args()
    rows = []
    print(f"{'lens':16} {'set':5} {'readable':>8} {'labelled':>8} {'complete':>9} {'corners':>7} {'RMS px':>7} "
          f"{'>1px':>4} {'marker':>6} {'plain':>5} {'SB':>5} {'SB RMS':>6} {'ms ours':>7} {'ms SB':>6}")
    for k, fam in enumerate(a.families.split(",")):
        for diff in a.difficulties.split(","):
            r = run_set(fam, diff, a.n, a.seed + 10 * k)
            rows.append(r)
            fmt = lambda x: f"{x:.3f}" if x is not None else "-"
            print(f"{fam:16} {diff:5} {r['readable']:>8} {r['labelled_readable']:>8} "
                  f"{r['complete']:>4}/{r['whole']:<4} {r['corners']:>7} {fmt(r['rms_px']):>7} {r['wild']:>4} "
                  f"{r['marker_reported']:>6} {r['plain_labelled']:>5} {r['sb_found']:>5} {fmt(r['sb_rms_px']):>6} "
                  f"{r['ms_ours']:>7.0f} {r['ms_sb']:>6.0f}", flush=True)
    if a.json:
        a.json.write_text(json.dumps(rows, indent=1))
    return 1 if any(r["wild"] or r["marker_reported"] for r in rows) else 0


if __name__ == "__main__":
    raise SystemExit(main())
