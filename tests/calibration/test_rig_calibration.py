"""The multi-camera synthetic renderer and `calibrate rig` (small sets, reduced RGB resolution)."""
from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from calibration.extrinsics.cad import CAMERAS
from platform_tools.rig.frames import Pose

REPO = Path(__file__).resolve().parents[2]


def run(*args):
    return subprocess.run([sys.executable, "-m", "calibration.cli", *args], cwd=REPO, capture_output=True, text=True)


@pytest.fixture(scope="module")
def rigset(tmp_path_factory):
    from calibration.rigsynth import render_rig_dataset
    out = tmp_path_factory.mktemp("rigsynth") / "set"
    render_rig_dataset(out, n=6, seed=3, rgb_scale=0.4)
    return out


@pytest.mark.slow
def test_truth_and_images(rigset):
    truth = json.loads((rigset / "truth.json").read_text())
    assert len(truth["sets"]) == 6 and truth["rgb_scale"] == 0.4
    for c, cam in truth["cameras"].items():
        assert 0.5 < cam["cad_to_true_mm"] < 4 and 0.2 < cam["cad_to_true_deg"] < 1.0
        files = sorted((rigset / c).iterdir())
        assert len(files) == 6
        img = cv2.imread(str(files[0]), cv2.IMREAD_UNCHANGED)
        if c.startswith("zed"):
            assert img.dtype == np.uint8 and img.shape == (480, 768, 3)     # 1920x1200 at 0.4
            assert cam["intrinsics"][0] == pytest.approx(1920 / 1920 * 2.2 / 3.0e-3 * 0.4)
        else:
            assert img.dtype == np.uint16 and img.shape == (512, 640)
    from calibration.detect import detect_corners
    st = truth["sets"][0]
    img = cv2.cvtColor(cv2.imread(str(rigset / st["files"]["zed_left"])), cv2.COLOR_BGR2GRAY)
    d = detect_corners(img, (10, 7))
    err = np.linalg.norm(d.corners - np.array(st["corners"]["zed_left"]), axis=1)
    assert d.complete and np.sqrt(np.mean(err ** 2)) < 0.3


@pytest.mark.slow
def test_rig_refines_towards_the_truth(rigset, tmp_path):
    out = tmp_path / "cal"
    r = run("rig", "--images", str(rigset), "--out", str(out), "--json", "-q", "--tolerance-mm", "0.5")
    assert r.returncode == 0, r.stderr
    rep = json.loads(r.stdout)
    assert rep["sets_used"] == 6
    assert any("from its CAD pose" in w for w in rep["warnings"])   # a tolerance of 0.5 mm warns (-q: not on stderr)
    truth = json.loads((rigset / "truth.json").read_text())
    T_true = {c: Pose.from_rt(truth["cameras"][c]["rt_cam_rig_true_m"], metres=True).inverse() for c in CAMERAS}
    import mrcal
    for c, frame in CAMERAS.items():
        m = mrcal.cameramodel(str(out / f"{frame.removesuffix('_optical')}.cameramodel"))
        T_ref = Pose.from_rt(m.extrinsics_rt_fromref(), metres=True).inverse()
        cad_zl = Pose.from_rt(truth["cameras"]["zed_left"]["rt_cam_rig_cad_m"], metres=True).inverse()
        got = cad_zl.inverse() @ T_ref          # relative to the anchor (the ZED left camera at its CAD pose)
        want = T_true["zed_left"].inverse() @ T_true[c]
        d = got.inverse() @ want
        assert np.linalg.norm(d.t) < 1.0 and d.angle_deg() < 0.1, (c, d)
    for th in ("thermal_left", "thermal_right"):
        for depth in ("1.5m", "5m"):
            row = rep["rgb_to_thermal_reprojection"][th][depth]
            assert row["cad_vs_refined"]["rms_px"] > 1.0          # CAD is ~0.5 deg off: several px
    assert (out / "rig.urdf").is_file() and (out / "report.json").is_file()


def _from_cad_mm(out: Path, truth: dict) -> dict[str, float]:
    """How far each thermal camera's refined pose is from CAD relative to the ZED left camera (mm)."""
    import mrcal
    cad = {c: Pose.from_rt(truth["cameras"][c]["rt_cam_rig_cad_m"], metres=True).inverse() for c in CAMERAS}
    d = {}
    for c in ("thermal_left", "thermal_right"):
        m = mrcal.cameramodel(str(out / f"{CAMERAS[c].removesuffix('_optical')}.cameramodel"))
        got = cad["zed_left"].inverse() @ Pose.from_rt(m.extrinsics_rt_fromref(), metres=True).inverse()
        d[c] = float(np.linalg.norm(((cad["zed_left"].inverse() @ cad[c]).inverse() @ got).t))
    return d


@pytest.mark.slow
def test_rig_uses_the_stack_up_as_its_prior(rigset, tmp_path, rig):
    # the same sets solved with the stack-up's prior, a looser printer's, and none: the prior holds the
    # thermal cameras towards CAD, less when the printer is looser, not at all with --prior none
    from calibration.extrinsics.prior import stack_up_priors
    truth = json.loads((rigset / "truth.json").read_text())
    loose = "printing.printer.tolerance_mm=0.6"
    runs = {}
    for name, extra in (("stack-up", []), ("loose", ["--set", loose]), ("none", ["--prior", "none"])):
        r = run("rig", "--images", str(rigset), "--out", str(tmp_path / name), "--json", "-q", *extra)
        assert r.returncode == 0, r.stderr
        runs[name] = (json.loads(r.stdout), _from_cad_mm(tmp_path / name, truth))
    rep = runs["stack-up"][0]
    want = stack_up_priors(rig)
    for c, s in rep["prior"]["sigma_optical_mm_deg"].items():
        assert s[:3] == pytest.approx(list(want[c].sigma_optical[:3]), rel=1e-4)
    loose_sigma = runs["loose"][0]["prior"]["sigma_optical_mm_deg"]["thermal_left"]
    assert loose_sigma[0] > rep["prior"]["sigma_optical_mm_deg"]["thermal_left"][0] * 1.3
    assert runs["none"][0]["prior"] == {"source": "none", "sigmas_from_cad": {}, "sigma_optical_mm_deg": {}}
    # the synthetic rig is 1.3-2.9 mm from CAD: several sigma of the stack-up, and said so
    assert all(v > 4.48 for v in rep["prior"]["sigmas_from_cad"].values())
    assert any("sigma from its CAD pose" in w for w in rep["warnings"])
    for c in ("thermal_left", "thermal_right"):
        held, looser, free = (runs[k][1][c] for k in ("stack-up", "loose", "none"))
        assert held < looser < free, (c, held, looser, free)


def _copy(src: Path, dst: Path) -> Path:
    shutil.copytree(src, dst, ignore=shutil.ignore_patterns("truth*"))
    return dst


def _blank(path: Path) -> None:
    img = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    cv2.imwrite(str(path), np.full_like(img, img.flat[0]))


def _bad(args, tmp_path, *words):
    out = tmp_path / "out"
    r = run("rig", "--out", str(out), *args)
    assert r.returncode == 2, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in r.stderr, r.stderr
    for w in words:
        assert w in lines[0], lines[0]
    assert not out.exists()
    return lines[0]


@pytest.mark.slow
def test_missing_camera(rigset, tmp_path):
    d = _copy(rigset, tmp_path / "set")
    shutil.rmtree(d / "thermal_right")
    _bad(["--images", str(d)], tmp_path, "thermal_right/")


@pytest.mark.slow
def test_timestamps_that_do_not_pair(rigset, tmp_path):
    d = _copy(rigset, tmp_path / "set")
    f = sorted((d / "thermal_left").iterdir())[2]
    f.rename(f.with_name(f"{int(f.stem) + 40_000_000}.png"))          # 40 ms late
    _bad(["--images", str(d)], tmp_path, "do not pair")


@pytest.mark.slow
def test_names_that_do_not_pair(rigset, tmp_path):
    d = tmp_path / "set"
    for c in CAMERAS:
        (d / c).mkdir(parents=True)
        for k, f in enumerate(sorted((rigset / c).iterdir())[:3]):
            shutil.copy(f, d / c / f"set{k}.png")
    (d / "zed_right" / "set2.png").rename(d / "zed_right" / "other.png")
    _bad(["--images", str(d)], tmp_path, "same name")


@pytest.mark.slow
def test_board_seen_by_one_camera_only(rigset, tmp_path):
    d = _copy(rigset, tmp_path / "set")
    for c in ("zed_right", "thermal_left", "thermal_right"):
        for f in (d / c).iterdir():
            _blank(f)
    _bad(["--images", str(d)], tmp_path, "more than one camera")


@pytest.mark.slow
def test_thermal_never_sees_the_board(rigset, tmp_path):
    d = _copy(rigset, tmp_path / "set")
    for f in (d / "thermal_right").iterdir():
        _blank(f)
    _bad(["--images", str(d)], tmp_path, "thermal_right", "0 set(s)")


@pytest.mark.slow
def test_overlapping_rig(rigset, tmp_path):
    _bad(["--images", str(rigset), "--set", "sensors.thermal.pose.xyz_mm=[0,0,-5]"], tmp_path, "overlap")
