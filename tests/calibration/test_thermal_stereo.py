"""`calibrate thermal-stereo` and calibration/stereo: the thermal pair's pose, rectification and epipolar
error, on stereo views of a known truth pose between two truth lenses of the stereographic family (closed
form in calibration/synth/truth_lens.py, not mrcal's or OpenCV's model code, and not the OPENCV8 family the
project's mono solver defaults to). The mono models given to the command are the truth lenses as
.cameramodel files (LENSMODEL_STEREOGRAPHIC, written by calibration/synth/truth_files.py), so what is
tested is the pair's solve, not a mono calibration."""
from __future__ import annotations

import dataclasses
import json
import shutil

import cv2
import mrcal
import numpy as np
import pytest

from calibration.cli import main
from calibration.synth.truth_families import truth_lens
from calibration.synth.truth_files import write_cameramodel
from platform_tools.rig.frames import Pose, rotvec_to_matrix

BOARD = (10, 7)
SQUARE = 0.04
NOISE_PX = 0.03
# the truth pose is the designed one (config/rig.yaml, through the CAD model in the command) moved by
# 1.7 mm and 0.6 deg: a rig built off its design


def cad_pose() -> Pose:
    """The right optical frame in the left one as the rig description places them (the CAD model places
    them there too; the command reads the CAD model, which costs seconds)."""
    from platform_tools.rig import load_rig
    return load_rig().T("thermal_left_optical", "thermal_right_optical")


def truth_pose(T_cad: Pose) -> Pose:
    axis = np.array([0.3, 0.8, -0.5])
    return T_cad @ Pose(rotvec_to_matrix(np.radians(0.6) * axis / np.linalg.norm(axis)), np.array([1.2, -0.8, 0.9]))


def truth_lenses():
    """(left, right) RadialLens: the stereographic truth lens and a second one with its own focal length and
    principal point (two cameras of one make)."""
    left = truth_lens("stereographic")
    right = dataclasses.replace(left, fx=left.fx * 1.004, fy=left.fy * 1.003, cx=left.cx + 2.5, cy=left.cy - 1.8,
                                name="stereographic, the right camera")
    return left, right


def as_model(lens, rt=None):
    from calibration.synth.truth_files import mrcal_equivalent
    from platform_tools.rig.cameras import camera_model
    return camera_model(*mrcal_equivalent(lens), lens.size, rt)


def board_points() -> np.ndarray:
    j, i = np.mgrid[0:BOARD[1], 0:BOARD[0]]
    return np.stack([i.ravel() * SQUARE, j.ravel() * SQUARE, np.zeros(BOARD[0] * BOARD[1])], axis=1)


def sample_poses(rng, lenses, T_left_right: Pose, n: int, margin: float = 8.0):
    """n board poses (R, t: board -> left camera, metres) 0.45-1.3 m ahead, tilted up to 35 deg, each seen
    whole by both cameras with ``margin`` px; and the true corners (n, H*W, 2) in each."""
    pts = board_points()
    centre = pts.mean(0)
    T_right_left = T_left_right.inverse()
    poses, ql, qr = [], [], []
    while len(poses) < n:
        d = rng.uniform(0.45, 1.3)
        az, el = np.radians(rng.uniform(-28, 28)), np.radians(rng.uniform(-22, 22))
        v = np.array([np.tan(az), np.tan(el), 1.0])
        v /= np.linalg.norm(v)
        tilt = rng.normal(size=3)
        R = rotvec_to_matrix(tilt / np.linalg.norm(tilt) * np.radians(35) * np.sqrt(rng.uniform()))
        t = d * v + np.array([0.06, 0.0, 0.0]) - R @ centre
        pl = pts @ R.T + t
        pr = T_right_left.apply(pl * 1000.0) / 1000.0
        a, b = lenses[0].project(pl), lenses[1].project(pr)
        W, H = lenses[0].size
        if all(np.all((q[:, 0] > margin) & (q[:, 0] < W - 1 - margin) & (q[:, 1] > margin) &
                      (q[:, 1] < H - 1 - margin)) for q in (a, b)):
            poses.append((R, t))
            ql.append(a)
            qr.append(b)
    return poses, np.array(ql), np.array(qr)


def observations(ql, qr):
    from calibration.stereo.pairs import StereoObservations
    return StereoObservations([f"{k:03d}" for k in range(len(ql))], ql, qr, np.ones(ql.shape[:2]),
                              np.ones(qr.shape[:2]), BOARD, SQUARE)


@pytest.fixture(scope="module")
def poses_cad():
    return cad_pose()


# ---------------------------------------------------------------- the solve on exact corners + noise
@pytest.fixture(scope="module")
def noisy_views(poses_cad):
    lenses = truth_lenses()
    T_true = truth_pose(poses_cad)
    rng = np.random.default_rng(5)
    _, ql, qr = sample_poses(rng, lenses, T_true, 12)
    return lenses, T_true, ql, qr, ql + rng.normal(0, NOISE_PX, ql.shape), qr + rng.normal(0, NOISE_PX, qr.shape)


def test_rows_agree_exactly_at_the_true_pose(noisy_views):
    """The epipolar measure itself: exact corners through the true lenses and pose land on one rectified row."""
    from calibration.stereo import rectify
    lenses, T_true, ql, qr, _, _ = noisy_views
    models = (as_model(lenses[0]), as_model(lenses[1], T_true.inverse().rt(metres=True)))
    rect = rectify.rectified_models(models)
    dy = rectify.row_disparity(models, rect, ql, qr)
    assert dy.size == ql.shape[0] * ql.shape[1]
    assert np.abs(dy).max() < 1e-6
    # and it sees a wrong pose: 0.1 deg about the baseline's normal moves the rows apart
    wrong = (models[0], as_model(lenses[1], (T_true @ Pose(rotvec_to_matrix(np.radians([0.1, 0, 0])),
                                                            np.zeros(3))).inverse().rt(metres=True)))
    assert rectify.epipolar_stats(rectify.row_disparity(wrong, rectify.rectified_models(wrong), ql, qr))["rms_px"] > 0.3


def test_solve_recovers_the_true_pose_within_1mm_and_0p05deg(noisy_views, poses_cad):
    from calibration.stereo import rectify
    from calibration.stereo.solve import pose_difference, solve_pair
    lenses, T_true, _, _, ql, qr = noisy_views
    seed = poses_cad.inverse().rt(metres=True)
    sol = solve_pair(observations(ql, qr), (as_model(lenses[0]), as_model(lenses[1])), seed)
    err = pose_difference(T_true, sol.T_left_right)
    assert err["translation_mm"] < 1.0 and err["rotation_deg"] < 0.05, err
    assert abs(err["baseline_mm"] - err["seed_baseline_mm"]) < 0.2
    from_cad = pose_difference(poses_cad, sol.T_left_right)
    assert from_cad["translation_mm"] > 1.0 and from_cad["rotation_deg"] > 0.3     # it did move off the seed
    assert all(NOISE_PX < r < 2 * NOISE_PX for r in sol.rms_px)                     # ~ sqrt(2) x 0.03
    rect = rectify.rectified_models(sol.models)
    epi = rectify.epipolar_stats(rectify.row_disparity(sol.models, rect, ql, qr))
    assert 0.5 * NOISE_PX < epi["rms_px"] < 2.5 * NOISE_PX, epi       # the row difference of two noisy corners
    seed_models = (as_model(lenses[0]), as_model(lenses[1], seed))
    at_cad = rectify.epipolar_stats(rectify.row_disparity(seed_models, rectify.rectified_models(seed_models), ql, qr))
    assert at_cad["rms_px"] > 20 * epi["rms_px"], at_cad


def test_refining_the_intrinsics_repairs_an_off_mono_model(noisy_views, poses_cad):
    """A right mono model 0.4 % off in focal length: held, it biases the pose; refined jointly, the pose
    comes back within the target."""
    from calibration.stereo.solve import pose_difference, solve_pair
    lenses, T_true, _, _, ql, qr = noisy_views
    off = dataclasses.replace(lenses[1], fx=lenses[1].fx * 1.004, fy=lenses[1].fy * 1.004)
    seed = poses_cad.inverse().rt(metres=True)
    models = (as_model(lenses[0]), as_model(off))
    held = solve_pair(observations(ql, qr), models, seed)
    refined = solve_pair(observations(ql, qr), models, seed, refine_intrinsics=True)
    e_held = pose_difference(T_true, held.T_left_right)
    e_ref = pose_difference(T_true, refined.T_left_right)
    assert held.rms_px[1] > 1.5 * refined.rms_px[1]
    assert e_ref["translation_mm"] < 1.0 and e_ref["rotation_deg"] < 0.05, e_ref
    assert e_held["translation_mm"] > 1.0 > e_ref["translation_mm"] and e_ref["rotation_deg"] < 0.05, (e_held, e_ref)
    assert refined.models[1].intrinsics()[1][0] == pytest.approx(lenses[1].fx, rel=5e-4)


def test_too_few_shared_views_is_refused(noisy_views, poses_cad):
    from calibration.stereo.solve import StereoSolveError, solve_pair
    lenses, _, _, _, ql, qr = noisy_views
    qr = qr.copy()
    qr[3:] = np.nan                               # the right camera saw only three of the poses
    with pytest.raises(StereoSolveError, match=r"3 of 12 board poses seen by both"):
        solve_pair(observations(ql, qr), (as_model(lenses[0]), as_model(lenses[1])),
                   poses_cad.inverse().rt(metres=True))


# ---------------------------------------------------------------- the command on rendered images
def render_pairs(root, lenses, T_true, n: int = 8, seed: int = 21):
    """n stereo pairs of a heated 10x7 board rendered through ``lenses`` at ``T_true`` (calibration/synth's
    renderer and microbolometer, "easy" look) into root/set/left and root/set/right; the true corners."""
    from calibration.synth.board import Board
    from calibration.synth.difficulty import level
    from calibration.synth.poses import BoardView
    from calibration.synth.render import render_image
    from calibration.synth.sensor import Sensor
    rng = np.random.default_rng(seed)
    poses, ql, qr = sample_poses(rng, lenses, T_true, n)
    diff = level("easy")
    board = Board(*BOARD, SQUARE)
    T_right_left = T_true.inverse()
    for side, lens, q in (("left", lenses[0], ql), ("right", lenses[1], qr)):
        (root / "set" / side).mkdir(parents=True)
        sensor = Sensor.make(np.random.default_rng([seed, len(side)]), lens.size[::-1], diff)
        for k, (R, t) in enumerate(poses):
            if side == "right":
                R, t = T_right_left.R @ R, T_right_left.R @ t + T_right_left.t / 1000.0
            img, _, _ = render_image(np.random.default_rng([seed, k, len(side)]), lens, board,
                                     BoardView(R, t, q[k], False), diff, sensor)
            cv2.imwrite(str(root / "set" / side / f"{k:03d}.png"), img)
    return ql, qr


@pytest.fixture(scope="module")
def rendered(tmp_path_factory, poses_cad):
    """8 stereo pairs through the two truth lenses at the truth pose (render_pairs), the two mono models
    and the truth."""
    root = tmp_path_factory.mktemp("stereo")
    lenses = truth_lenses()
    T_true = truth_pose(poses_cad)
    ql, qr = render_pairs(root, lenses, T_true)
    for side, lens in (("left", lenses[0]), ("right", lenses[1])):
        write_cameramodel(root / f"{side}.cameramodel", lens, f"truth lens of the {side} camera")
    return root, lenses, T_true, ql, qr


def run_cli(capsys, *args):
    code = main(["thermal-stereo", *args])
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.mark.slow
def test_command_recovers_the_pair_and_writes_what_mrcal_and_opencv_read(rendered, tmp_path, capsys):
    root, lenses, T_true, ql, qr = rendered
    out = tmp_path / "pair"
    code, stdout, err = run_cli(capsys, "--left", str(root / "left.cameramodel"), "--right",
                                str(root / "right.cameramodel"), "--images", str(root / "set"), "--board", "10x7",
                                "--square", str(SQUARE), "--out", str(out), "--json", "-q")
    assert code == 0, err
    rep = json.loads(stdout)
    assert rep["shared_views"] == 8 and rep["pairs"] == 8
    # the pair as mrcal reads it back from the files
    L, R = (mrcal.cameramodel(str(out / f)) for f in ("left.cameramodel", "right.cameramodel"))
    assert np.allclose(L.extrinsics_rt_fromref(), 0)
    T = Pose.from_rt(R.extrinsics_rt_fromref(), metres=True).inverse()
    D = T_true.inverse() @ T
    assert np.linalg.norm(T.t - T_true.t) < 1.0 and D.angle_deg() < 0.05, (T.t, T_true.t, D.angle_deg())
    assert rep["from_cad"]["translation_mm"] > 1.0 and not rep["warnings"]
    assert rep["epipolar"]["rms_px"] < 0.1 and rep["epipolar"]["p99_px"] < 0.3, rep["epipolar"]
    assert rep["epipolar_at_cad"]["rms_px"] > 10 * rep["epipolar"]["rms_px"]
    # the maps rectify the images: the rows of the corners found in both rectified views agree
    from calibration.detect import detect_corners
    rect = [mrcal.cameramodel(str(out / f"rectified_{s}.cameramodel")) for s in ("left", "right")]
    maps = [np.load(out / f"rectification_{s}.npy") for s in ("left", "right")]
    Wr, Hr = (int(x) for x in rect[0].imagersize())
    assert all(m.shape == (Hr, Wr, 2) and m.dtype == np.float32 for m in maps)
    found = []
    for s, m in zip(("left", "right"), maps):
        img = cv2.imread(str(root / "set" / s / "000.png"), cv2.IMREAD_UNCHANGED)
        d = detect_corners(cv2.remap(img, m, None, cv2.INTER_LINEAR), BOARD)
        assert d.complete, (s, d.reason)
        found.append(d.corners)
    dy = found[0][:, 1] - found[1][:, 1]
    assert np.sqrt(np.mean(dy ** 2)) < 0.3, dy
    dx = found[0][:, 0] - found[1][:, 0]
    assert np.all(dx > 5)                    # a disparity along the rows, the right view shifted left


@pytest.mark.slow
def test_missing_right_image_is_one_line_exit_2(rendered, tmp_path, capsys):
    root = rendered[0]
    images = tmp_path / "set"
    shutil.copytree(root / "set", images)
    (images / "right" / "004.png").unlink()
    out = tmp_path / "pair"
    code, _, err = run_cli(capsys, "--left", str(root / "left.cameramodel"), "--right", str(root / "right.cameramodel"),
                           "--images", str(images), "--board", "10x7", "--square", str(SQUARE), "--out", str(out))
    assert code == 2
    assert err.count("\n") == 1 and "left/004.png: no image named 004.* in" in err, err
    assert not out.exists()


def test_models_of_different_imager_sizes_are_refused(tmp_path, capsys):
    from platform_tools.rig.cameras import scaled
    left, right = truth_lenses()
    write_cameramodel(tmp_path / "left.cameramodel", left, "truth lens of the left camera")
    scaled(as_model(right), (320, 256)).write(str(tmp_path / "small.cameramodel"))
    (tmp_path / "set" / "left").mkdir(parents=True)
    (tmp_path / "set" / "right").mkdir()
    out = tmp_path / "pair"
    code, _, err = run_cli(capsys, "--left", str(tmp_path / "left.cameramodel"), "--right",
                           str(tmp_path / "small.cameramodel"), "--images", str(tmp_path / "set"), "--board", "10x7",
                           "--square", str(SQUARE), "--out", str(out))
    assert code == 2
    assert err.count("\n") == 1 and "small.cameramodel: a 320x256 model" in err and "is 640x512" in err, err
    assert not out.exists()


@pytest.mark.slow
def test_too_few_shared_views_is_one_line_exit_2(rendered, tmp_path, capsys):
    root = rendered[0]
    images = tmp_path / "set"
    for s in ("left", "right"):
        (images / s).mkdir(parents=True)
        for k in (0, 1):
            shutil.copy(root / "set" / s / f"{k:03d}.png", images / s)
    out = tmp_path / "pair"
    code, _, err = run_cli(capsys, "--left", str(root / "left.cameramodel"), "--right", str(root / "right.cameramodel"),
                           "--images", str(images), "--board", "10x7", "--square", str(SQUARE), "--out", str(out))
    assert code == 2
    assert err.count("\n") == 1 and "2 of 2 board poses seen by both cameras (at least 5 needed)" in err, err
    assert not out.exists()
