"""Benchmark: refined extrinsics against the truth with N synchronised synthetic sets.

Renders a rig set (calibration.rigsynth: true extrinsics about 2 mm / 0.5 deg from CAD per camera),
runs `calibrate rig` on it, and prints per camera: the refined pose's error against the truth, and
the CAD-to-truth difference against the CAD-to-refined one (what `calibrate rig` reports), all
relative to the anchor (the ZED left camera; the data cannot see where the rig's origin is). Also
the RGB-to-thermal reprojection error at 1.5 m and 5 m of the CAD and the refined extrinsics,
against the true mapping. Target: 0.05 deg and 1 mm.

    .venv/bin/python bench/bench_extrinsics.py [--n 30] [--seed 11] [--rgb-scale 0.5]
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from calibration.extrinsics.cad import CAMERAS  # noqa: E402
from platform_tools.rig.cameras import camera_model  # noqa: E402
from calibration.extrinsics.solve import mapping_error_px, rgb_to_thermal_px  # noqa: E402
from calibration.rigsynth import render_rig_dataset  # noqa: E402
from platform_tools.rig.frames import Pose  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=30)
    ap.add_argument("--seed", type=int, default=11)
    ap.add_argument("--rgb-scale", type=float, default=0.5)
    ap.add_argument("--zed-intrinsics", default="fixed", choices=("fixed", "solved"))
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.monotonic()
        truth = render_rig_dataset(Path(tmp) / "set", n=a.n, seed=a.seed, rgb_scale=a.rgb_scale)
        t1 = time.monotonic()
        r = subprocess.run([sys.executable, "-m", "calibration.cli", "rig", "--images", f"{tmp}/set", "--out",
                            f"{tmp}/cal", "--json", "-q", "--zed-intrinsics", a.zed_intrinsics],
                           cwd=REPO, capture_output=True, text=True)
        t2 = time.monotonic()
        if r.returncode != 0:
            print(r.stderr)
            return r.returncode
        rep = json.loads(r.stdout)
        import mrcal
        refined = {}
        for c, frame in CAMERAS.items():
            m = mrcal.cameramodel(f"{tmp}/cal/{frame.removesuffix('_optical')}.cameramodel")
            refined[c] = Pose.from_rt(m.extrinsics_rt_fromref(), metres=True).inverse()
    cams = truth["cameras"]
    true = {c: Pose.from_rt(cams[c]["rt_cam_rig_true_m"], metres=True).inverse() for c in CAMERAS}
    cad = {c: Pose.from_rt(cams[c]["rt_cam_rig_cad_m"], metres=True).inverse() for c in CAMERAS}

    def rel(T):          # relative to the anchor camera
        return {c: T["zed_left"].inverse() @ T[c] for c in CAMERAS}
    tr, cr, rr = rel(true), rel(cad), rel(refined)
    print(f"{a.n} sets (seed {a.seed}, RGB at {a.rgb_scale} scale, ZED intrinsics {a.zed_intrinsics}); "
          f"render {t1 - t0:.0f} s, calibrate rig {t2 - t1:.1f} s; RMS px " +
          ", ".join(f"{c} {v:.3f}" for c, v in rep["rms_px"].items()))
    print("relative to the ZED left camera (the anchor):")
    print(f"{'camera':14s} | {'refined vs truth':>20s} | {'CAD vs truth':>18s} | {'CAD vs refined':>18s} | "
          f"{'recovery error':>18s}")
    worst = [0.0, 0.0, 0.0, 0.0]
    for c in list(CAMERAS)[1:]:
        e = tr[c].inverse() @ rr[c]                      # refined against truth
        dt = cr[c].inverse() @ tr[c]                     # the CAD-to-truth difference
        dr = cr[c].inverse() @ rr[c]                     # the CAD-to-refined difference (reported)
        rec_mm = float(np.linalg.norm(dt.t - dr.t))
        rec_deg = (dt.inverse() @ dr).angle_deg()
        worst = [max(worst[0], np.linalg.norm(e.t)), max(worst[1], e.angle_deg()), max(worst[2], rec_mm),
                 max(worst[3], rec_deg)]
        print(f"{c:14s} | {np.linalg.norm(e.t):7.3f} mm {e.angle_deg():7.4f} deg | {np.linalg.norm(dt.t):6.3f} mm "
              f"{dt.angle_deg():6.3f} deg | {np.linalg.norm(dr.t):6.3f} mm {dr.angle_deg():6.3f} deg | "
              f"{rec_mm:6.3f} mm {rec_deg:6.4f} deg")
    print(f"worst: refined vs truth {worst[0]:.3f} mm {worst[1]:.4f} deg; CAD difference recovered to "
          f"{worst[2]:.3f} mm {worst[3]:.4f} deg (target 1 mm, 0.05 deg): "
          f"{'MET' if worst[0] < 1 and worst[1] < 0.05 and worst[2] < 1 and worst[3] < 0.05 else 'NOT MET'}")
    lens = {c: camera_model(cams[c]["lensmodel"], cams[c]["intrinsics"], tuple(cams[c]["imagersize"]))
            for c in CAMERAS}
    print("RGB (ZED left) to thermal reprojection error against the true mapping (true lenses), RMS / max px:")
    for th in ("thermal_left", "thermal_right"):
        row = []
        for d in (1.5, 5.0):
            ref = rgb_to_thermal_px(lens["zed_left"], lens[th], tr[th].inverse(), d)
            ec = mapping_error_px(ref, rgb_to_thermal_px(lens["zed_left"], lens[th], cr[th].inverse(), d))
            er = mapping_error_px(ref, rgb_to_thermal_px(lens["zed_left"], lens[th], rr[th].inverse(), d))
            row.append(f"{d:g} m: CAD {ec['rms_px']:.2f}/{ec['max_px']:.2f}, refined {er['rms_px']:.3f}/{er['max_px']:.3f}")
        print(f"  {th:14s} " + "; ".join(row))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
