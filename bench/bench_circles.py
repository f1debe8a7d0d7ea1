"""Benchmark: --target circle-grid / asymmetric-circle-grid, ours beside OpenCV's cv2.findCirclesGrid
on the same synthetic images through four truth lens families, and the disc-centroid bias.

    .venv/bin/python bench/bench_circles.py [--n 8] [--seed 50] [--json FILE]

Per truth lens (opencv8, kannala-brandt, stereographic, boson-published), target (a 7x5 symmetric
grid; an 8x7 asymmetric one, OpenCV's patternSize (4, 7)) and difficulty (real, hard): n views drawn
as calibrate synth draws board poses (partial views over the image's edges included), 0.04 m
spacing, disc radius 0.3 spacings, rendered by calibration/synth/circles_render.py. Columns: views
with every disc in view and no hand ("whole"); of those, ours labelled and OpenCV found; views ours
labelled in all; centres reported; RMS of ours against the true centre projections, raw and with
the disc-centroid bias (calibration/detect/circles.py disc_centroid_bias, from the truth lens and
pose) taken off; the worst corrected centre; mislabels (a centre more than 1.5 px from its own truth
raw, or reported where no disc is: must be 0); OpenCV's RMS on its found views (each centre to the
nearest true centre: its ordering is not checked); ms per image (median, one core) and the ratio.
OpenCV gets 8-bit images (0.5-99.5 percentile stretch), both polarities tried (its blob detector
looks for one colour), and its SimpleBlobDetector's area limits opened to 5-20000 px; ours reads the
16-bit counts.

Then the bias itself, from the lens model alone: a disc facing the camera 0.4 m away at a field
angle (along the image's horizontal and its diagonal), radius 6, 12 and 20 mm, through the
Kannala-Brandt truth lens: |centroid - projected centre| px; and, from the rendered "real" sets,
the mean raw error and mean predicted bias of ours per field-angle band.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
os.environ.setdefault("OMP_NUM_THREADS", "1")
cv2.setNumThreads(1)

from calibration.detect.circles import detect_circle_grid, disc_centroid_bias  # noqa: E402
from calibration.synth.circles_render import circle_board  # noqa: E402
from calibration.synth.difficulty import level  # noqa: E402
from calibration.synth.lens import project, unproject  # noqa: E402
from calibration.synth.poses import sample_view  # noqa: E402
from calibration.synth.targets_render import render_views  # noqa: E402
from calibration.synth.truth_families import FAMILIES, truth_lens  # noqa: E402

BOARDS = {"circle-grid": (7, 5), "asymmetric-circle-grid": (8, 7)}
SPACING_M = 0.04
BANDS_DEG = (0, 20, 35, 45, 55, 70)


def to8(img):
    lo, hi = np.percentile(img, [0.5, 99.5])
    return np.clip((img.astype(np.float32) - lo) / max(hi - lo, 1) * 255, 0, 255).astype(np.uint8)


def opencv_grid(img8: np.ndarray, kind: str, board) -> np.ndarray | None:
    """cv2.findCirclesGrid on both polarities: (n, 2) centres or None."""
    p = cv2.SimpleBlobDetector_Params()
    p.minArea, p.maxArea = 5, 20000
    p.blobColor = 255
    det = cv2.SimpleBlobDetector_create(p)
    if kind == "circle-grid":
        size, flags = board, cv2.CALIB_CB_SYMMETRIC_GRID
    else:
        size, flags = (board[0] // 2, board[1]), cv2.CALIB_CB_ASYMMETRIC_GRID
    for im in (img8, 255 - img8):
        ok, c = cv2.findCirclesGrid(im, size, flags=flags, blobDetector=det)
        if ok:
            return c.reshape(-1, 2)
    return None


def field_angle_deg(lens, q: np.ndarray) -> np.ndarray:
    v = unproject(q, lens)
    return np.degrees(np.arccos(np.clip(v[..., 2], -1, 1)))


def run_set(family: str, kind: str, difficulty: str, n: int, seed: int, bands: dict) -> dict:
    board = BOARDS[kind]
    lens = truth_lens(family)
    b = circle_board(kind, *board, SPACING_M)
    pres = b.present()
    diff = level(difficulty)
    views = [sample_view(np.random.default_rng([seed, k]), lens, b, diff) for k in range(n)]
    rendered = render_views(lens, b, difficulty, seed=seed, views=views)
    r = dict(family=family, kind=kind, difficulty=difficulty, n=n, whole=0, ours_whole=0, cv_whole=0, ours_views=0,
             centres=0, mislabels=0)
    raw, cor, cv_err, t_ours, t_cv = [], [], [], [], []
    for view, (img, q, occ) in zip(views, rendered):
        t0 = time.perf_counter()
        det = detect_circle_grid(img, board, kind)
        t_ours.append(time.perf_counter() - t0)
        img8 = to8(img)
        t0 = time.perf_counter()
        c = opencv_grid(img8, kind, board)
        t_cv.append(time.perf_counter() - t0)
        whole = bool(np.isfinite(q[pres, 0]).all()) and not occ.any()
        r["whole"] += whole
        r["ours_whole"] += whole and det.detected
        r["cv_whole"] += whole and c is not None
        if c is not None:
            truth = q[pres & np.isfinite(q[:, 0])]
            d = np.min(np.linalg.norm(c[:, None, :] - truth[None], axis=2), axis=1)
            cv_err.extend(d.tolist())
        if not det.detected:
            continue
        r["ours_views"] += 1
        rep = np.isfinite(det.corners[:, 0])
        r["mislabels"] += int(np.sum(rep & (~pres | np.isnan(q[:, 0]))))
        rep &= np.isfinite(q[:, 0])
        bias = disc_centroid_bias(lambda p: project(p, lens), view.R, view.t, b.corners(), b.radius)
        e = np.linalg.norm(det.corners[rep] - q[rep], axis=1)
        ec = np.linalg.norm(det.corners[rep] - bias[rep] - q[rep], axis=1)
        r["mislabels"] += int(np.sum(e > 1.5))
        r["centres"] += int(rep.sum())
        raw.extend(e.tolist())
        cor.extend(ec.tolist())
        if difficulty == "real":
            ang = field_angle_deg(lens, q[rep])
            for a, er, bi in zip(ang, e, np.linalg.norm(bias[rep], axis=1)):
                k = int(np.searchsorted(BANDS_DEG, a, side="right")) - 1
                bands.setdefault((family, k), []).append((er, bi))
    rms = lambda x: float(np.sqrt(np.mean(np.square(x)))) if x else None
    r.update(rms_raw=rms(raw), rms_corrected=rms(cor), worst_corrected=max(cor) if cor else None, cv_rms=rms(cv_err),
             ms_ours=1e3 * float(np.median(t_ours)), ms_cv=1e3 * float(np.median(t_cv)))
    r["time_ratio_ours_over_cv"] = r["ms_ours"] / max(r["ms_cv"], 1e-9)
    return r


def bias_table(family: str = "kannala-brandt", dist: float = 0.4) -> list[dict]:
    """|disc centroid - projected centre| px of a disc 0.4 m away, facing the camera or tilted 45 deg
    about its vertical axis, by field angle (along the image's horizontal and diagonal) and radius."""
    lens = truth_lens(family)
    W, H = lens.imagersize()
    f = float(lens.intrinsics()[1][0])
    rows = []
    for direction, (dx, dy) in (("horizontal", (1.0, 0.0)), ("diagonal", (W / math.hypot(W, H), H / math.hypot(W, H)))):
        for angle in (0, 10, 20, 30, 40, 47, 55):
            th = math.radians(angle)
            z = np.array([math.sin(th) * dx, math.sin(th) * dy, math.cos(th)])
            q = project(z[None], lens)[0]
            if not (0 <= q[0] <= W - 1 and 0 <= q[1] <= H - 1):
                continue
            x = np.array([1.0, 0.0, 0.0]) - z[0] * z
            x /= np.linalg.norm(x)
            facing = np.stack([x, np.cross(z, x), z], axis=1)
            for tilt in (0, 45):
                c, s_ = math.cos(math.radians(tilt)), math.sin(math.radians(tilt))
                R = facing @ np.array([[c, 0, s_], [0, 1, 0], [-s_, 0, c]])
                row = dict(direction=direction, angle_deg=angle, tilt_deg=tilt,
                           pixel=(round(float(q[0]), 1), round(float(q[1]), 1)))
                for rad_mm in (6, 12, 20):
                    bias = disc_centroid_bias(lambda p: project(p, lens), R, dist * z, np.zeros((1, 3)), rad_mm / 1000)
                    row[f"r{rad_mm}mm_px"] = float(np.linalg.norm(bias[0]))
                rows.append(row)
    return rows, {r: round(2 * r / 1000 / dist * f, 1) for r in (6, 12, 20)}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=8)
    ap.add_argument("--seed", type=int, default=50)
    ap.add_argument("--families", default=",".join(FAMILIES))
    ap.add_argument("--kinds", default=",".join(BOARDS))
    ap.add_argument("--difficulties", default="real,hard")
    ap.add_argument("--json", type=Path)
    a = ap.parse_args()
    rows, bands = [], {}
    fmt = lambda x: f"{x:.3f}" if x is not None else "-"
    print(f"{'lens':16} {'target':22} {'set':5} {'whole':>5} {'ours':>4} {'cv':>4} {'views':>5} {'centres':>7} "
          f"{'raw':>6} {'corr':>6} {'worst':>6} {'mis':>3} {'cv RMS':>6} {'ms ours':>7} {'ms cv':>6}")
    for k, fam in enumerate(a.families.split(",")):
        for kind in a.kinds.split(","):
            for diff in a.difficulties.split(","):
                r = run_set(fam, kind, diff, a.n, a.seed + 10 * k, bands)
                rows.append(r)
                print(f"{fam:16} {kind:22} {diff:5} {r['whole']:>5} {r['ours_whole']:>4} {r['cv_whole']:>4} "
                      f"{r['ours_views']:>5} {r['centres']:>7} {fmt(r['rms_raw']):>6} {fmt(r['rms_corrected']):>6} "
                      f"{fmt(r['worst_corrected']):>6} {r['mislabels']:>3} {fmt(r['cv_rms']):>6} {r['ms_ours']:>7.0f} "
                      f"{r['ms_cv']:>6.0f}", flush=True)
    table, diam = bias_table()
    print(f"\nbias of the disc's centroid, Kannala-Brandt truth lens, disc at 0.4 m (px; imaged diameter on the "
          f"axis: {diam} px for radius 6 / 12 / 20 mm):")
    for t in table:
        print(f"  {t['direction']:10} {t['angle_deg']:>3} deg tilt {t['tilt_deg']:>2} at {t['pixel']}: r 6 mm "
              f"{t['r6mm_px']:.3f}, 12 mm {t['r12mm_px']:.3f}, 20 mm {t['r20mm_px']:.3f}")
    print("\nrendered 'real' sets, ours, per field-angle band: mean raw error / mean predicted bias (px), centres")
    band_rows = []
    for (fam, k), v in sorted(bands.items()):
        v = np.array(v)
        band_rows.append(dict(family=fam, band_deg=(BANDS_DEG[k], BANDS_DEG[k + 1]), raw_px=float(v[:, 0].mean()),
                              bias_px=float(v[:, 1].mean()), n=len(v)))
        print(f"  {fam:16} {BANDS_DEG[k]:>2}-{BANDS_DEG[k + 1]:<2} deg: {v[:, 0].mean():.3f} / {v[:, 1].mean():.3f} "
              f"({len(v)})")
    if a.json:
        a.json.write_text(json.dumps(dict(sets=rows, bias=table, bands=band_rows), indent=1, default=str))
    return 1 if any(r["mislabels"] for r in rows) else 0


if __name__ == "__main__":
    raise SystemExit(main())
