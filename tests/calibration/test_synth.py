"""The synthetic thermal images: exact truth through a real mrcal lens, files in real formats."""
from __future__ import annotations

import json
import math

import cv2
import mrcal
import numpy as np
import pytest

from calibration.synth import LEVELS, render_dataset
from calibration.synth.board import Board
from calibration.synth.lens import nominal_thermal_lens, unproject, unproject_radial
from platform_tools.rig import load_rig
from platform_tools.rig.cameras import camera_model, imagersize


@pytest.fixture(scope="module")
def lens():
    return nominal_thermal_lens(load_rig())


def test_lens_follows_the_rig_description(lens):
    rig = load_rig()
    spec = rig.camera_model("boson_640_4p9mm")
    lensmodel, intrinsics = lens.intrinsics()
    assert isinstance(lens, mrcal.cameramodel) and lensmodel == "LENSMODEL_OPENCV8"
    assert imagersize(lens) == (spec.width_px, spec.height_px)
    assert intrinsics[0] == pytest.approx(rig.focal_px(spec))
    # the horizontal field of view through the principal point is the rig's HFoV (within 1 deg)
    cy = intrinsics[3]
    v = unproject(np.array([[-0.5, cy], [spec.width_px - 0.5, cy]]), lens)
    hfov = math.degrees(math.atan2(-v[0, 0], v[0, 2]) + math.atan2(v[1, 0], v[1, 2]))
    assert hfov == pytest.approx(spec.hfov_deg.value, abs=1.0)


def test_lens_follows_a_changed_rig():
    rig = load_rig(overrides=("camera_models.boson_640_4p9mm.hfov_deg.value=90",))
    L = nominal_thermal_lens(rig)
    cy = L.intrinsics()[1][3]
    v = unproject(np.array([[-0.5, cy], [639.5, cy]]), L)
    assert math.degrees(math.atan2(-v[0, 0], v[0, 2]) + math.atan2(v[1, 0], v[1, 2])) == pytest.approx(90, abs=1.0)


def test_fast_unprojection_is_mrcals(lens):
    rng = np.random.default_rng(3)
    q = rng.uniform([-0.5, -0.5], [639.5, 511.5], size=(500, 2))
    v = unproject_radial(q, lens)
    ref = mrcal.unproject(q, *lens.intrinsics())
    ref /= np.linalg.norm(ref, axis=1, keepdims=True)
    assert np.abs(v - ref).max() < 1e-9
    assert np.abs(mrcal.project(v, *lens.intrinsics()) - q).max() < 1e-8


def test_board_pattern_is_a_checker_with_heat_spread():
    b = Board(4, 3, 0.04)
    # square centres alternate; the top-left square is +1; the border is 0
    assert b.pattern(np.array([-0.02]), np.array([-0.02]), 0.001)[0] == pytest.approx(1.0)
    assert b.pattern(np.array([0.02]), np.array([-0.02]), 0.001)[0] == pytest.approx(-1.0)
    assert b.pattern(np.array([-0.05]), np.array([0.06]), 0.001)[0] == pytest.approx(0.0, abs=1e-9)
    # on an inner edge the blurred signal is halfway; spreading widens the transition
    assert b.pattern(np.array([0.0]), np.array([-0.02]), 0.002)[0] == pytest.approx(0.0, abs=1e-9)
    sharp = b.pattern(np.array([0.002]), np.array([-0.02]), 0.0005)[0]
    soft = b.pattern(np.array([0.002]), np.array([-0.02]), 0.004)[0]
    assert sharp < soft < 0


@pytest.mark.slow
def test_dataset_files_and_truth(synth_set, lens):
    out = synth_set("real", n=4, seed=7)
    truth = json.loads((out / "truth.json").read_text())
    assert truth["lensmodel"] == "LENSMODEL_OPENCV8" and truth["imagersize"] == [640, 512]
    assert truth["board"] == {"width": 10, "height": 7, "square_m": 0.04}
    assert truth["difficulty"] == "real" and truth["seed"] == 7 and len(truth["images"]) == 4
    model = mrcal.cameramodel(str(out / "truth.cameramodel"))
    assert model.intrinsics()[0] == "LENSMODEL_OPENCV8"
    assert np.allclose(model.intrinsics()[1], truth["intrinsics"])
    obj = Board(10, 7, 0.04).corners()
    for im in truth["images"]:
        img = cv2.imread(str(out / im["file"]), cv2.IMREAD_UNCHANGED)
        assert img.dtype == np.uint16 and img.shape == (512, 640)
        # the truth is the exact projection of the corner points under rt_cam_board
        rt = np.array(im["rt_cam_board"])
        q = mrcal.project(mrcal.transform_point_rt(rt, obj), *model.intrinsics())
        got = np.array([c if c is not None else [np.nan, np.nan] for c in im["corners"]])
        seen = np.isfinite(got[:, 0])
        assert np.abs(got[seen] - q[seen]).max() < 1e-6   # rt is rounded through Rodrigues
        inside = (q[:, 0] >= -0.5) & (q[:, 0] <= 639.5) & (q[:, 1] >= -0.5) & (q[:, 1] <= 511.5)
        assert np.array_equal(seen, inside)
        assert im["visible"] == int(seen.sum())


@pytest.mark.slow
def test_same_seed_same_images_other_seed_other_images(tmp_path):
    a = render_dataset(tmp_path / "a", n=1, difficulty="hard", seed=11, show_progress=False)
    b = render_dataset(tmp_path / "b", n=1, difficulty="hard", seed=11, show_progress=False)
    c = render_dataset(tmp_path / "c", n=1, difficulty="hard", seed=12, show_progress=False)
    assert a == b and a != c
    assert (tmp_path / "a" / "000.png").read_bytes() == (tmp_path / "b" / "000.png").read_bytes()


@pytest.mark.slow
def test_difficulty_changes_the_look(synth_set):
    """Easy boards have more contrast over noise than hard ones, measured on the images."""
    def cnr(folder):
        vals = []
        truth = json.loads((folder / "truth.json").read_text())
        for im in truth["images"]:
            img = cv2.imread(str(folder / im["file"]), cv2.IMREAD_UNCHANGED).astype(float)
            q = np.array([c for c in im["corners"] if c is not None])
            x0, y0 = np.maximum(q.min(0).astype(int), 0)
            x1, y1 = q.max(0).astype(int)
            patch = img[y0:y1, x0:x1]
            noise = np.median(np.abs(np.diff(img, 2, axis=1))) / 0.6745 / np.sqrt(6)
            vals.append((np.percentile(patch, 95) - np.percentile(patch, 5)) / max(noise, 1e-3))
        return np.median(vals)
    assert cnr(synth_set("easy", n=3, seed=2)) > 2 * cnr(synth_set("hard", n=3, seed=2))
    assert LEVELS["hard"].max_tilt_deg > LEVELS["real"].max_tilt_deg > LEVELS["easy"].max_tilt_deg


@pytest.mark.slow
def test_partial_boards_in_real_sets(tmp_path):
    truth = render_dataset(tmp_path / "s", n=12, difficulty="real", seed=3, show_progress=False)
    vis = [im["visible"] for im in truth["images"]]
    assert any(v < 70 for v in vis) and any(v == 70 for v in vis)
    assert all(v >= 0.35 * 70 for v in vis)


@pytest.mark.slow
def test_custom_lens_is_the_truth(tmp_path):
    intr = (400.0, 400.0, 320.0, 256.0, -0.05, 0.01, 1e-4, -1e-4, 0, 0, 0, 0)
    lens = camera_model("LENSMODEL_OPENCV8", intr, (640, 512))
    truth = render_dataset(tmp_path / "s", n=1, difficulty="easy", seed=1, lens=lens, show_progress=False)
    assert truth["intrinsics"] == list(intr)
    assert mrcal.cameramodel(str(tmp_path / "s" / "truth.cameramodel")).intrinsics()[1].tolist() == list(intr)
    # the same lens as a (lensmodel, intrinsics, imagersize) tuple renders the same truth
    again = render_dataset(tmp_path / "t", n=1, difficulty="easy", seed=1, lens=("LENSMODEL_OPENCV8", intr, (640, 512)),
                           show_progress=False)
    assert again == truth


@pytest.mark.slow
@pytest.mark.parametrize("args, message", [
    (["--board", "10"], "--board"),
    (["--board", "1x7"], "--board"),
    (["--square", "-1"], "--square"),
    (["--n", "0"], "--n"),
    (["--camera", "zed_x_top"], "--camera"),
])
def test_synth_command_bad_input(calibrate, tmp_path, args, message):
    r = calibrate("synth", "--out", str(tmp_path / "o"), "--n", "1", *args)
    assert r.returncode == 2, r.stderr
    assert message in r.stderr and "Traceback" not in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()


@pytest.mark.slow
def test_synth_command_json(calibrate, tmp_path):
    r = calibrate("synth", "--out", str(tmp_path / "o"), "--n", "2", "--difficulty", "easy", "--board", "8x6",
                  "--square", "0.05", "--seed", "4", "--json")
    assert r.returncode == 0, r.stderr
    summary = json.loads(r.stdout)
    assert summary["images"] == 2 and summary["board"] == {"width": 8, "height": 6, "square_m": 0.05}
    assert sorted(p.name for p in (tmp_path / "o").iterdir()) == ["000.png", "001.png", "truth.cameramodel",
                                                                  "truth.json"]
