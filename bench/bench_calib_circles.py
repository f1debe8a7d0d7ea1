"""Benchmark: calibration from circle grids, end to end, with and without the centroid-bias correction in
the solve, beside OpenCV's cv2.findCirclesGrid + cv2.fisheye.calibrate on the same images.

    .venv/bin/python bench/bench_calib_circles.py [--n 40] [--seed 60] [--families kannala-brandt,stereographic]
                                                 [--kind asymmetric-circle-grid] [--difficulty real] [--work DIR]

Per truth lens (calibration/synth/truth_families.py; neither is the solver's default family): n views of
the grid (asymmetric: 10x9 lattice, OpenCV's patternSize (5, 9); symmetric: 7x5) of 0.03 m spacing,
discs of 0.3 spacings, drawn as `calibrate synth` draws poses (partial views over the image's edges
included), rendered by calibration/synth/circles_render.py as 16-bit PNGs. Then, on the same files:

  ours raw        calibration.thermal.pipeline.calibrate (what `calibrate thermal --target ...` runs: our
                  detector, the default solver and lens model chosen by the data), --no-centroid-correction
  ours corrected  the same with the correction (the default): each disc's centroid bias iterated out
  ours/opencv     --solver opencv (cv2.fisheye on our centres), raw and corrected
  OpenCV          cv2.findCirclesGrid (8-bit, 0.5-99.5 percentile stretch, both polarities, blob areas
                  5-20000 px) + cv2.fisheye.calibrate with OpenCV's own point order and object points

Columns: views used; centre RMS against the true centres' projections (ours: the centres the solve
used, raw or corrected; OpenCV: each found centre to the nearest true centre); the model error
against the truth (calibration.lens.compare: projection difference after the best-fit rotation) RMS
over the whole image and the central 80%; fx error; correction rounds; the time, and its ratio to
OpenCV's. 2 cores shared: read the ratios.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "bench"))
os.environ.setdefault("OMP_NUM_THREADS", "1")

from bench_circles import opencv_grid, to8  # noqa: E402

from calibration.intrinsics.circle_bias import projector  # noqa: E402
from calibration.intrinsics.quiet import quiet_stderr  # noqa: E402
from calibration.lens import kannala_brandt as kb  # noqa: E402
from calibration.lens.compare import compare  # noqa: E402
from calibration.synth.circles_render import circle_board  # noqa: E402
from calibration.synth.difficulty import level  # noqa: E402
from calibration.synth.lens import unproject  # noqa: E402
from calibration.synth.poses import sample_view  # noqa: E402
from calibration.synth.targets_render import render_views  # noqa: E402
from calibration.synth.truth_families import truth_lens  # noqa: E402

BOARDS = {"asymmetric-circle-grid": (10, 9), "circle-grid": (7, 5)}
SPACING_M = 0.03
FOCAL_SEED_PX = None       # the rig description's, read once in main()


def render(family: str, kind: str, difficulty: str, n: int, seed: int, out: Path):
    """(lens, board, truth centres per file name) of n rendered views written to ``out``."""
    lens = truth_lens(family)
    b = circle_board(kind, *BOARDS[kind], SPACING_M)
    diff = level(difficulty)
    views = [sample_view(np.random.default_rng([seed, k]), lens, b, diff) for k in range(n)]
    out.mkdir(parents=True, exist_ok=True)
    truth = {}
    for k, (img, q, _occ) in enumerate(render_views(lens, b, difficulty, seed=seed, views=views)):
        name = f"{k:03d}.png"
        cv2.imwrite(str(out / name), img)
        truth[name] = np.where(b.present()[:, None], q, np.nan)
    return lens, b, truth


def centre_rms(obs, truth) -> float:
    err = []
    for name, c in zip(obs.names, obs.corners):
        t = truth[name]
        ok = np.isfinite(c[:, 0]) & np.isfinite(t[:, 0])
        err.extend(np.linalg.norm(c[ok] - t[ok], axis=1).tolist())
    return float(np.sqrt(np.mean(np.square(err)))) if err else float("nan")


def model_error(project, lens) -> tuple[float, float]:
    c = compare(project, lambda q: unproject(np.asarray(q, float), lens), lens.size)
    return c.rms_px, c.central_rms_px


def run_ours(src: Path, kind: str, board, solver: str, radius_m: float | None, rig, lens, truth) -> dict:
    from calibration.thermal.pipeline import calibrate
    spec = rig.camera_model(rig.desc.sensors.thermal.camera_model)
    t0 = time.perf_counter()
    with quiet_stderr():
        obs, sol, out = calibrate(str(src), board, SPACING_M, solver=solver, lens_model=None,
                                  focal_px=rig.focal_px(spec), expected_size=lens.size, camera_name="thermal",
                                  rig_hash="bench", target=kind, circle_radius_m=radius_m)
    dt = time.perf_counter() - t0
    whole, central = model_error(projector(sol), lens)
    cc = sol.centroid_correction
    return dict(views=sol.observations.n, centre_rms_px=centre_rms(sol.observations, truth), whole_px=whole,
                central_px=central, fx_err_px=float(sol.intrinsics[0] - lens.fx), lensmodel=sol.lensmodel,
                rounds=None if cc is None else cc["rounds"], converged=None if cc is None else cc["converged"],
                verdict=out.verdict.grade, time_s=dt)


def run_opencv(src: Path, kind: str, board, lens, truth) -> dict:
    t0 = time.perf_counter()
    if kind == "circle-grid":
        cols, rows = board
        objp = np.array([[j * SPACING_M, i * SPACING_M, 0] for i in range(rows) for j in range(cols)], float)
    else:
        cols, rows = board[0] // 2, board[1]
        objp = np.array([[(2 * j + i % 2) * SPACING_M, i * SPACING_M, 0] for i in range(rows) for j in range(cols)],
                        float)
    op, ip, err = [], [], []
    for name in sorted(truth):
        img = cv2.imread(str(src / name), cv2.IMREAD_UNCHANGED)
        c = opencv_grid(to8(img), kind, board)
        if c is None:
            continue
        t = truth[name][np.isfinite(truth[name][:, 0])]
        err.extend(np.min(np.linalg.norm(c[:, None] - t[None], axis=2), axis=1).tolist())
        op.append(objp.reshape(1, -1, 3))
        ip.append(c.reshape(1, -1, 2).astype(np.float64))
    W, H = lens.size
    K = np.array([[FOCAL_SEED_PX, 0, (W - 1) / 2], [0, FOCAL_SEED_PX, (H - 1) / 2], [0, 0, 1.0]])
    r = dict(views=len(op), centre_rms_px=float(np.sqrt(np.mean(np.square(err)))) if err else float("nan"))
    try:
        _, K, D, _, _ = cv2.fisheye.calibrate(
            op, ip, (W, H), K, np.zeros((4, 1)),
            flags=cv2.fisheye.CALIB_RECOMPUTE_EXTRINSIC | cv2.fisheye.CALIB_FIX_SKEW | cv2.fisheye.CALIB_USE_INTRINSIC_GUESS,
            criteria=(cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, 200, 1e-12))
    except cv2.error as exc:
        return dict(r, error=str(exc).strip().splitlines()[-1], time_s=time.perf_counter() - t0)
    p = np.array([K[0, 0], K[1, 1], K[0, 2], K[1, 2], *D.ravel()])
    whole, central = model_error(lambda v: kb.project(v, p), lens)
    return dict(r, whole_px=whole, central_px=central, fx_err_px=float(p[0] - lens.fx), lensmodel=kb.NAME,
                time_s=time.perf_counter() - t0)


def fmt(family: str, method: str, r: dict, base: float) -> str:
    f = lambda k, d=3: "-" if r.get(k) is None else f"{r[k]:.{d}f}"
    rounds = "-" if r.get("rounds") is None else f"{r['rounds']}{'' if r.get('converged') else ' (not converged)'}"
    lm = {"KANNALA_BRANDT": "KB", "LENSMODEL_OPENCV8": "OPENCV8"}.get(r.get("lensmodel"), r.get("lensmodel", ""))
    return (f"| {family} | {method} ({lm}) | {r['views']} | {f('centre_rms_px')} | {f('whole_px')} / {f('central_px')} "
            f"| {f('fx_err_px')} | {rounds} | {r.get('verdict', '-')} | {r['time_s']:.1f} ({r['time_s'] / base:.1f}) |"
            + (f" {r['error']}" if "error" in r else ""))


def main(argv=None) -> int:
    global FOCAL_SEED_PX
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=40)
    ap.add_argument("--seed", type=int, default=60)
    ap.add_argument("--families", default="kannala-brandt,stereographic")
    ap.add_argument("--kind", default="asymmetric-circle-grid", choices=tuple(BOARDS))
    ap.add_argument("--difficulty", default="real")
    ap.add_argument("--work", type=Path, default=None)
    ap.add_argument("--json", type=Path, default=None)
    a = ap.parse_args(argv)
    from platform_tools.rig import load_rig
    from calibration.targets.spec import CIRCLE_RADIUS_SPACING
    rig = load_rig()
    FOCAL_SEED_PX = rig.focal_px(rig.camera_model(rig.desc.sensors.thermal.camera_model))
    work = a.work or Path(tempfile.mkdtemp(prefix="bench_calib_circles."))
    board = BOARDS[a.kind]
    radius = CIRCLE_RADIUS_SPACING * SPACING_M
    print(f"{a.n} '{a.difficulty}' views per lens, {a.kind} {board[0]}x{board[1]}, spacing {SPACING_M} m, disc radius "
          f"{1000 * radius:g} mm, seed {a.seed}, work {work}", flush=True)
    print("\n| truth lens | method | views | centre RMS px | model error whole / central 80 % px | fx error px | "
          "rounds | verdict | time s (x OpenCV) |\n|---|---|---|---|---|---|---|---|---|", flush=True)
    rows = []
    for k, fam in enumerate(a.families.split(",")):
        src = work / fam
        lens, _b, truth = render(fam, a.kind, a.difficulty, a.n, a.seed + 10 * k, src)
        res = {"OpenCV findCirclesGrid + fisheye": run_opencv(src, a.kind, board, lens, truth)}
        for method, solver, rad in (("ours raw", "mrcal", None), ("ours corrected", "mrcal", radius),
                                    ("ours/opencv raw", "opencv", None), ("ours/opencv corrected", "opencv", radius)):
            res[method] = run_ours(src, a.kind, board, solver, rad, rig, lens, truth)
        base = res["OpenCV findCirclesGrid + fisheye"]["time_s"]
        for method, r in res.items():
            print(fmt(fam, method, r, base), flush=True)
            rows.append(dict(family=fam, method=method, **r))
    if a.json:
        a.json.write_text(json.dumps(rows, indent=1, default=str))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
