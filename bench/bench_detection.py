"""Benchmark: heated-checkerboard detection on synthetic thermal sets, side by side with OpenCV's
findChessboardCornersSB and mrgingham, on the same images.

    .venv/bin/python bench/bench_detection.py [--n 40] [--seeds 100,200,300] [--families opencv8,kannala-brandt,...]
        [--work build/bench_detection]

Each seed renders its own four sets (under WORK/seed<S>/ when more than one seed is given); the
table comes per seed and then pooled over the seeds (boards and corners summed, RMS over all corners,
median time over all images).

Truth lenses (--families, default all of calibration/synth/truth_families.py: opencv8, the solver's
own family and this bench's anchor, then kannala-brandt, stereographic and boson-published): each
family renders its own sets, under WORK/<family>/ (the opencv8 sets stay where they were, WORK/ or
WORK/seed<S>/). Sets: "real" and "hard" with the default 10x7 board, and "real" / "hard" with a 7x7 board (mrgingham
only detects square boards). Per detector and set: share of fully visible, unoccluded boards found
complete; corner RMS error against the truth (px, complete boards only, best of the two 180 deg
orderings for the other tools since their order convention differs); corners > 1 px off; ms per image
(one process, one core). For ours also every board it reports, partial ones included: corners
mislabelled (> 3 px from their own truth), and how many of the visible corners within 80 px of an
image corner it reports correctly (where a fisheye fit needs data). OpenCV and mrgingham get 8-bit images (0.5-99.5 percentile stretch), as
they need; ours reads the 16-bit counts.

Diagnostics (the metrics stay the same): --only-ours skips OpenCV and mrgingham; --missed names, per
set, the fully visible boards ours did not find complete (with the labels missing and the reason a
view was dropped) and any board with mislabelled corners.
"""
from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
os.environ.setdefault("OMP_NUM_THREADS", "1")
cv2.setNumThreads(1)

from calibration.detect import detect_corners  # noqa: E402
from calibration.synth import render_dataset    # noqa: E402
from calibration.synth.truth_families import FAMILIES, truth_lens  # noqa: E402


def to8(img):
    lo, hi = np.percentile(img, [0.5, 99.5])
    return np.clip((img.astype(np.float32) - lo) / max(hi - lo, 1) * 255, 0, 255).astype(np.uint8)


def score(pred, truth):
    """(rms-able errors, n wrong) of a complete prediction vs truth, best of the two orderings."""
    best = None
    for p in (pred, pred[::-1]):
        e = np.linalg.norm(p - truth, axis=1)
        if best is None or np.nanmedian(e) < np.nanmedian(best):
            best = e
    return best


CORNER_ZONE = 80.0     # px from an image corner: where a fisheye fit most needs data


def run_ours(folder, files, board, partial=None, reasons=None):
    """Complete boards per file (None otherwise); every board found, partial or not, goes into
    ``partial`` (file -> corners with NaN) when given, and the reason a board was dropped into
    ``reasons`` (file -> text, empty if kept)."""
    out, ts = {}, []
    for f in files:
        img = cv2.imread(str(folder / f), cv2.IMREAD_UNCHANGED)
        t = time.perf_counter()
        d = detect_corners(img, board)
        ts.append(time.perf_counter() - t)
        out[f] = d.corners if d.complete else None
        if partial is not None:
            partial[f] = d.corners
        if reasons is not None:
            reasons[f] = d.reason
    return out, ts


def print_missed(truth, found, reasons):
    """Diagnostics (--missed): the fully visible, unoccluded boards ours did not find complete
    (file, corners found, the grid labels missing, the reason if the view was dropped), and every
    board with mislabelled corners (more than 3 px from their own truth)."""
    W, H = truth["board"]["width"], truth["board"]["height"]
    for im in truth["images"]:
        c = found.get(im["file"])
        q = np.array([x if x is not None else [np.nan, np.nan] for x in im["corners"]], float)
        rep = np.isfinite(c[:, 0]) if c is not None else np.zeros(W * H, bool)
        if im["visible"] == W * H and not im["occluded"] and not rep.all():
            miss = [(k % W, k // W) for k in np.flatnonzero(~rep)]
            more = f" (+{len(miss) - 8} more)" if len(miss) > 8 else ""
            why = reasons.get(im["file"], "")
            print(f"    missed {im['file']}: {int(rep.sum())} of {W * H}, missing {miss[:8]}{more}"
                  + (f": {why}" if why else ""))
        if c is not None:
            with np.errstate(invalid="ignore"):
                wrong = rep & ~(np.linalg.norm(c - q, axis=1) <= 3.0)
            if wrong.any():
                print(f"    MISLABELLED {im['file']}: {[(k % W, k // W) for k in np.flatnonzero(wrong)]}")


def evaluate_all(truth, found):
    """Our every reported corner (partial boards too) against the truth: (mislabelled = reported
    more than 3 px from its own truth or where the truth is outside the image, reported within
    3 px, visible corners within CORNER_ZONE px of an image corner, of those reported)."""
    w, h = truth["imagersize"]
    wrong = ok = zone = zone_found = 0
    for im in truth["images"]:
        q = np.array([c if c is not None else [np.nan, np.nan] for c in im["corners"]], float)
        c = found.get(im["file"])
        if c is None:
            continue
        rep = np.isfinite(c[:, 0])
        with np.errstate(invalid="ignore"):
            e = np.linalg.norm(c - q, axis=1)
            good = rep & (e <= 3.0)
        wrong += int(np.sum(rep & ~good))
        ok += int(good.sum())
        vis = np.isfinite(q[:, 0])
        for cx, cy in ((0, 0), (w - 1, 0), (0, h - 1), (w - 1, h - 1)):
            with np.errstate(invalid="ignore"):
                near = vis & (np.hypot(q[:, 0] - cx, q[:, 1] - cy) < CORNER_ZONE)
            zone += int(near.sum())
            zone_found += int(np.sum(near & good))
    return dict(mislabelled=wrong, reported=ok, zone=zone, zone_found=zone_found)


def run_opencv(folder, files, board):
    out, ts = {}, []
    for f in files:
        img = to8(cv2.imread(str(folder / f), cv2.IMREAD_UNCHANGED))
        t = time.perf_counter()
        ok, c = cv2.findChessboardCornersSB(img, board, flags=cv2.CALIB_CB_EXHAUSTIVE | cv2.CALIB_CB_ACCURACY)
        ts.append(time.perf_counter() - t)
        out[f] = c.reshape(-1, 2).astype(float) if ok else None
    return out, ts


def run_mrgingham(folder, files, board, work):
    if board[0] != board[1]:
        return None, None
    d8 = work / (folder.name + "_8bit")
    d8.mkdir(parents=True, exist_ok=True)
    for f in files:
        cv2.imwrite(str(d8 / f), to8(cv2.imread(str(folder / f), cv2.IMREAD_UNCHANGED)))
    t = time.perf_counter()
    p = subprocess.run(["mrgingham", "--jobs", "1", "--gridn", str(board[0]), str(d8 / "*.png")],
                       capture_output=True, text=True)
    total = time.perf_counter() - t
    rows = {}
    for line in p.stdout.splitlines():
        if line.startswith("#") or not line.strip():
            continue
        name, x, y = line.split()[:3]
        rows.setdefault(Path(name).name, []).append((np.nan if x == "-" else float(x), np.nan if y == "-" else float(y)))
    out = {f: (np.array(rows[f]) if f in rows and len(rows[f]) == board[0] * board[1] and
               np.isfinite(np.array(rows[f])).all() else None) for f in files}
    return out, [total / len(files)] * len(files)


def evaluate(folder, truth, results):
    W, H = truth["board"]["width"], truth["board"]["height"]
    full = [im for im in truth["images"] if im["visible"] == W * H and not im["occluded"]]
    found, errs, wrong = 0, [], 0
    for im in full:
        q = np.array(im["corners"], float)
        pred = results.get(im["file"])
        if pred is None:
            continue
        found += 1
        e = score(pred, q)
        wrong += int(np.sum(e > 1.0))
        errs.append(e[e <= 1.0])
    e = np.concatenate(errs) if errs else np.array([np.nan])
    return dict(full=len(full), found=found, rate=found / max(len(full), 1), rms=float(np.sqrt(np.mean(e ** 2))),
                wrong=wrong, n_err=int(np.sum(np.isfinite(e))), sse=float(np.nansum(e ** 2)))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=40)
    ap.add_argument("--seed", type=int, default=100, help="one seed (ignored with --seeds)")
    ap.add_argument("--seeds", type=str, default="", help="comma-separated seeds, e.g. 100,200,300")
    ap.add_argument("--work", type=Path, default=Path("build/bench_detection"))
    ap.add_argument("--families", type=str, default=",".join(FAMILIES),
                    help=f"comma-separated truth lenses (default {','.join(FAMILIES)})")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--reuse", action="store_true",
                    help="read sets already rendered under WORK (same --n and seed) instead of rendering them again")
    ap.add_argument("--only-ours", action="store_true", help="diagnostics: run our detector only")
    ap.add_argument("--missed", action="store_true",
                    help="diagnostics: name the fully visible boards ours missed, and any mislabelled corners")
    args = ap.parse_args(argv)
    sets = [("real", (10, 7)), ("hard", (10, 7)), ("real", (7, 7)), ("hard", (7, 7))]
    seeds = [int(x) for x in args.seeds.split(",") if x.strip()] or [args.seed]
    families = [x.strip() for x in args.families.split(",") if x.strip()]
    for fam in families:
        if fam not in FAMILIES:
            ap.error(f"--families {fam}: unknown truth lens; choose from {', '.join(FAMILIES)}")
    table = []
    for fam in families:
        base = args.work if fam == "opencv8" else args.work / fam
        if len(families) > 1:
            print(f"\ntruth lens {fam}", flush=True)
        for seed in seeds:
            rows = run_seed(args, seed, sets, base / f"seed{seed}" if len(seeds) > 1 else base,
                            None if fam == "opencv8" else truth_lens(fam))
            table += [dict(r, family=fam) for r in rows]
    if len(seeds) > 1:
        print(f"\npooled over seeds {','.join(map(str, seeds))}")
        pooled = []
        for fam, (diff, board) in ((f, s) for f in families for s in sets):
            name = f"{diff} {board[0]}x{board[1]}"
            for det in ("ours", "opencv_sb", "mrgingham"):
                rows = [r for r in table if r["set"] == name and r["detector"] == det and r["family"] == fam]
                if not rows:
                    continue
                row = dict(seed="pooled", family=fam, set=name, detector=det,
                           ms=float(np.median([r["ms"] for r in rows])),
                           **{k: sum(r[k] for r in rows) for k in ("full", "found", "wrong", "n_err", "sse")})
                row["rate"] = row["found"] / max(row["full"], 1)
                row["rms"] = float(np.sqrt(row["sse"] / max(row["n_err"], 1)))
                extra = ""
                if det == "ours":
                    row.update({k: sum(r[k] for r in rows) for k in ("mislabelled", "reported", "zone", "zone_found")})
                    extra = (f"  all boards: {row['reported']} corners, mislabelled {row['mislabelled']}; "
                             f"image-corner zones {row['zone_found']}/{row['zone']}")
                pooled.append(row)
                print(f"{fam[:8]:8s} {name:12s} {det:10s} complete {row['found']:3d}/{row['full']:3d} ({100 * row['rate']:5.1f}%)  "
                      f"rms {row['rms']:.3f} px  wrong>1px {row['wrong']:4d}  {row['ms']:7.1f} ms/image{extra}", flush=True)
        table += pooled
    args.work.mkdir(parents=True, exist_ok=True)
    (args.work / "results.json").write_text(json.dumps(table, indent=1))
    return 0


def run_seed(args, seed, sets, work, lens=None):
    """The four sets of one seed through ``lens`` (None: the nominal OPENCV8 lens)."""
    if len(args.seeds.split(",")) > 1:
        print(f"\nseed {seed}", flush=True)
    table = []
    for diff, board in sets:
        folder = work / f"{diff}_{board[0]}x{board[1]}"
        truth = json.loads((folder / "truth.json").read_text()) if (folder / "truth.json").exists() else {}
        if not (args.reuse and truth.get("seed") == seed and len(truth.get("images", ())) == args.n):
            truth = render_dataset(folder, n=args.n, difficulty=diff, board=board, seed=seed, lens=lens,
                                   show_progress=False)
        files = [im["file"] for im in truth["images"]]
        partial, reasons = {}, {}
        for name, fn in (("ours", lambda: run_ours(folder, files, board, partial, reasons)),
                         ("opencv_sb", lambda: run_opencv(folder, files, board)),
                         ("mrgingham", lambda: run_mrgingham(folder, files, board, work))):
            if args.only_ours and name != "ours":
                continue
            res, ts = fn()
            if res is None:
                continue
            row = dict(seed=seed, set=f"{diff} {board[0]}x{board[1]}", detector=name, ms=1000 * float(np.median(ts)),
                       **evaluate(folder, truth, res))
            extra = ""
            if name == "ours":
                row.update(evaluate_all(truth, partial))
                extra = (f"  all boards: {row['reported']} corners, mislabelled {row['mislabelled']}; "
                         f"image-corner zones {row['zone_found']}/{row['zone']}")
            table.append(row)
            print(f"{row['set']:12s} {name:10s} complete {row['found']:3d}/{row['full']:3d} ({100 * row['rate']:5.1f}%)  "
                  f"rms {row['rms']:.3f} px  wrong>1px {row['wrong']:4d}  {row['ms']:7.1f} ms/image{extra}", flush=True)
            if name == "ours" and args.missed:
                print_missed(truth, partial, reasons)
    ours = {r["set"]: r for r in table if r["detector"] == "ours"}
    print("\nratios (other / ours): time and rms")
    for r in table:
        if r["detector"] != "ours":
            o = ours[r["set"]]
            print(f"{r['set']:12s} {r['detector']:10s} time x{r['ms'] / o['ms']:.1f}  rms x{r['rms'] / o['rms']:.2f}")
    return table


if __name__ == "__main__":
    raise SystemExit(main())
