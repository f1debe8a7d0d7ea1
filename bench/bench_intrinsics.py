"""Thermal intrinsics accuracy, side by side with the reference tools, on the same images.

Renders a "real" synthetic set (default 40 images, a square 8x8 board so that mrgingham can run on it
too), then calibrates it several ways and compares each result with the true lens (projection
difference after the best-fit rotation, whole image and central 80%; calibration.lens.compare), with
calibrate thermal's verdict (ours only: the others have none) and the time, also as a ratio to ours:

  ours (default)  calibrate thermal (our detector + in-process mrcal, default lens model)
  ours/<model>    calibrate thermal --lens-model opencv8 | splined
  ours/opencv     calibrate thermal --solver opencv (our detector + cv2.fisheye)
  opencv          cv2.findChessboardCornersSB on 8-bit images + cv2.fisheye.calibrate
  mrgingham+mrcal mrgingham on 8-bit images + mrcal-calibrate-cameras (the command-line tool)

Usage: .venv/bin/python bench/bench_intrinsics.py [--n 40] [--seed 7] [--output y16|agc8] [--keep DIR]
Targets (issue 6): <= 0.1 px RMS whole image, <= 0.05 px central 80%.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import cv2
import mrcal
import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from calibration.lens import kannala_brandt as kb  # noqa: E402
from calibration.synth import render_dataset  # noqa: E402
from calibration.lens.compare import compare  # noqa: E402

BOARD = (8, 8)
SQUARE = 0.04


def _nominal_focal_px() -> float:
    """The seed calibrate thermal takes from the rig description (focal length / pixel pitch)."""
    from platform_tools.rig import load_rig
    rig = load_rig()
    return rig.focal_px(rig.camera_model(rig.desc.sensors.thermal.camera_model))


FOCAL = _nominal_focal_px()


def to8bit(src: Path, dst: Path) -> list[Path]:
    dst.mkdir(parents=True, exist_ok=True)
    out = []
    for p in sorted(src.glob("*.png")):
        img = cv2.imread(str(p), cv2.IMREAD_UNCHANGED).astype(np.float32)
        lo, hi = np.percentile(img, [1, 99])
        g = np.clip((img - lo) / max(hi - lo, 1) * 255, 0, 255).astype(np.uint8)
        cv2.imwrite(str(dst / p.name), g)
        out.append(dst / p.name)
    return out


def truth_unproject(truth):
    lm, it = truth.intrinsics()
    return lambda q: mrcal.unproject(np.ascontiguousarray(q), lm, it, normalize=True)


def mrcal_project(model):
    lm, it = model.intrinsics()
    return lambda v: mrcal.project(np.ascontiguousarray(v), lm, it)


def run_ours(src: Path, out: Path, solver: str, lens_model: str | None = None):
    t = time.perf_counter()
    cmd = [sys.executable, "-m", "calibration.cli", "thermal", "--images", str(src), "--board",
           f"{BOARD[0]}x{BOARD[1]}", "--square", str(SQUARE), "--out", str(out), "--solver", solver,
           "--json", "-q", "--exit-zero"] + (["--lens-model", lens_model] if lens_model else [])
    r = subprocess.run(cmd, cwd=REPO, capture_output=True, text=True)
    dt = time.perf_counter() - t
    if r.returncode != 0:
        return None, dt, r.stderr.strip().splitlines()[-1:]
    s = json.loads(r.stdout)
    if solver == "opencv" or s.get("lensmodel") == kb.NAME:     # the default may choose Kannala-Brandt
        p = np.array(s["intrinsics"])
        return (lambda v: kb.project(v, p)), dt, dict(_info(s), lensmodel=kb.NAME)
    m = mrcal.cameramodel(str(out / "thermal.cameramodel"))
    return mrcal_project(m), dt, dict(_info(s), lensmodel=m.intrinsics()[0])


def _info(s: dict) -> dict:
    v = s["verdict"]
    grade = v.get("grade") or ("trusted" if v["trustworthy"] else "not-trusted")   # older summaries: no grade
    return dict(images=s["n_images_used"], rejected=s["n_rejected_images"],
                verdict=f"{grade} ({100 * s['validity']['trusted_share']:.0f}% valid)",
                why=v["headline"][:110])


def run_opencv(files8: list[Path]):
    t = time.perf_counter()
    objp = np.zeros((1, BOARD[0] * BOARD[1], 3))
    objp[0, :, :2] = np.mgrid[0:BOARD[0], 0:BOARD[1]].T.reshape(-1, 2) * SQUARE
    op, ip = [], []
    size = None
    for f in files8:
        g = cv2.imread(str(f), cv2.IMREAD_GRAYSCALE)
        size = g.shape[::-1]
        ok, c = cv2.findChessboardCornersSB(g, BOARD, flags=cv2.CALIB_CB_EXHAUSTIVE | cv2.CALIB_CB_ACCURACY)
        if ok:
            op.append(objp.copy())
            ip.append(c.reshape(1, -1, 2).astype(np.float64))
    K = np.array([[FOCAL, 0, (size[0] - 1) / 2], [0, FOCAL, (size[1] - 1) / 2], [0, 0, 1.0]])
    try:
        _, K, D, _, _ = cv2.fisheye.calibrate(
            op, ip, size, K, np.zeros((4, 1)),
            flags=cv2.fisheye.CALIB_RECOMPUTE_EXTRINSIC | cv2.fisheye.CALIB_FIX_SKEW | cv2.fisheye.CALIB_USE_INTRINSIC_GUESS,
            criteria=(cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, 200, 1e-12))
    except cv2.error as exc:
        return None, time.perf_counter() - t, dict(images=len(op), error=str(exc).splitlines()[-1])
    p = np.array([K[0, 0], K[1, 1], K[0, 2], K[1, 2], *D.ravel()])
    return (lambda v: kb.project(v, p)), time.perf_counter() - t, dict(images=len(op))


def run_mrgingham(dir8: Path, out: Path):
    t = time.perf_counter()
    corners = out / "corners.vnl"
    out.mkdir(parents=True, exist_ok=True)
    with open(corners, "w") as f:
        subprocess.run(["mrgingham", "--gridn", str(BOARD[0]), "--jobs", "2", str(dir8 / "*.png")],
                       stdout=f, check=True)
    n = len({l.split()[0] for l in corners.read_text().splitlines()
             if l and not l.startswith("#") and l.split()[1] != "-"})
    r = subprocess.run(["mrcal-calibrate-cameras", "--corners-cache", str(corners), "--lensmodel",
                        "LENSMODEL_OPENCV8", "--focal", str(FOCAL), "--object-spacing", str(SQUARE),
                        "--object-width-n", str(BOARD[0]), "--outdir", str(out), str(dir8 / "*.png")],
                       capture_output=True, text=True, cwd=out)
    dt = time.perf_counter() - t
    if r.returncode != 0:
        return None, dt, dict(images=n, error=r.stderr.strip().splitlines()[-1:])
    return mrcal_project(mrcal.cameramodel(str(out / "camera-0.cameramodel"))), dt, dict(images=n)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=40)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--difficulty", default="real")
    ap.add_argument("--output", default="y16", choices=("y16", "agc8"),
                    help="y16: 16-bit counts; agc8: the same frames through the 8-bit AGC (calibration/synth/agc.py), "
                         "every method on the same 8-bit images (bench_calib_lenses.py runs both on every truth lens)")
    ap.add_argument("--keep", type=Path, default=None, help="work folder to keep (default: a temp folder)")
    args = ap.parse_args()
    work = args.keep or Path(tempfile.mkdtemp(prefix="bench_intrinsics."))
    src = work / "set"
    t = time.perf_counter()
    render_dataset(src, n=args.n, difficulty=args.difficulty, board=BOARD, square=SQUARE, seed=args.seed,
                   show_progress=False, output=args.output)
    print(f"rendered {args.n} '{args.difficulty}' {args.output} images, board {BOARD[0]}x{BOARD[1]}, in {time.perf_counter() - t:.1f} s: {src}")
    truth = mrcal.cameramodel(str(src / "truth.cameramodel"))
    size = tuple(int(x) for x in truth.imagersize())
    files8 = to8bit(src, work / "set8")

    rows = []
    for name, fn in [("ours (default)", lambda: run_ours(src, work / "ours_default", "mrcal")),
                     ("ours/opencv8", lambda: run_ours(src, work / "ours_opencv8", "mrcal", "opencv8")),
                     ("ours/splined", lambda: run_ours(src, work / "ours_splined", "mrcal", "splined")),
                     ("ours/opencv (KB)", lambda: run_ours(src, work / "ours_opencv", "opencv")),
                     ("OpenCV SB + fisheye", lambda: run_opencv(files8)),
                     ("mrgingham + mrcal-cc", lambda: run_mrgingham(work / "set8", work / "mrgingham"))]:
        proj, dt, info = fn()
        if proj is None:
            rows.append((name, None, dt, info))
            continue
        c = compare(proj, truth_unproject(truth), size)
        rows.append((name, c, dt, info))

    print(f"\n{'method':22s} {'images':>6s} {'RMS px':>8s} {'central80':>9s} {'worst px':>8s} {'time s':>7s} "
          f"{'xours':>6s}  verdict")
    base = rows[0][2]
    for name, c, dt, info in rows:
        if c is None:
            print(f"{name:22s} {info.get('images', 0):6d} {'failed':>8s} {'':9s} {'':8s} {dt:7.1f} "
                  f"{dt / base:6.2f}  {info}")
            continue
        print(f"{name:22s} {info.get('images', 0):6d} {c.rms_px:8.3f} {c.central_rms_px:9.3f} {c.max_px:8.3f} "
              f"{dt:7.1f} {dt / base:6.2f}  {info.get('verdict', '-')}")
    print("\nwhy (ours):")
    for name, c, dt, info in rows:
        if "why" in info:
            print(f"  {name}: {info.get('lensmodel', '')} {info['why']}")
    print("\ntargets: RMS <= 0.100 px, central 80% <= 0.050 px (projection difference vs the true lens)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
