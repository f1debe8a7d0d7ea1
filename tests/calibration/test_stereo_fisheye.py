"""calibrate thermal-stereo's cross-check against OpenCV's fisheye stereo functions for a Kannala-Brandt
pair (calibration/stereo/fisheye_check.py). The pair: two Kannala-Brandt truth lenses (closed form,
calibration/synth/truth_lens.py; the right one with its own focal length and principal point), corners
projected through them at a known pose plus 0.03 px noise; the mono models given are what `calibrate
thermal --solver opencv` writes for such a lens: the nearest OPENCV8 as the .cameramodel, the exact
lens as thermal_opencv.yaml (fisheye)."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from calibration import formats
from calibration.lens import kannala_brandt as kb
from calibration.synth.truth_families import truth_lens
from platform_tools.rig.frames import Pose, rotvec_to_matrix

from .test_thermal_stereo import (BOARD, SQUARE, board_points, cad_pose, observations, render_pairs, run_cli,
                                  sample_poses, truth_pose)

NOISE_PX = 0.03


def kb_pair():
    left = truth_lens("kannala-brandt")
    right = dataclasses.replace(left, fx=left.fx * 1.004, fy=left.fy * 1.003, cx=left.cx + 2.5, cy=left.cy - 1.8)
    return left, right


def written_files(lens, tmp_path, side):
    """(the .cameramodel, the thermal_opencv.yaml path) as calibrate thermal --solver opencv writes them."""
    from platform_tools.rig.cameras import camera_model
    _, p = lens.intrinsics()
    k = kb.KannalaBrandt(np.asarray(p, float), lens.size)
    o8 = formats.representation(k, "rational_polynomial")
    model = camera_model("LENSMODEL_OPENCV8", np.concatenate([[o8.K[0, 0], o8.K[1, 1], o8.K[0, 2], o8.K[1, 2]], o8.D]),
                         lens.size)
    path = tmp_path / f"{side}_opencv.yaml"
    path.write_text(formats.opencv_yaml(formats.representation(k, "equidistant"), lens.size, camera_name=side))
    return model, path


@pytest.fixture(scope="module")
def kb_views():
    T_cad = cad_pose()
    lenses = kb_pair()
    T_true = truth_pose(T_cad)
    rng = np.random.default_rng(8)
    _, ql, qr = sample_poses(rng, lenses, T_true, 12)
    return lenses, T_true, T_cad, ql + rng.normal(0, NOISE_PX, ql.shape), qr + rng.normal(0, NOISE_PX, qr.shape)


def _solve(kb_views, tmp_path):
    from calibration.stereo import fisheye_check, rectify
    from calibration.stereo.solve import solve_pair
    lenses, T_true, T_cad, ql, qr = kb_views
    (ml, pl), (mr, pr) = written_files(lenses[0], tmp_path, "left"), written_files(lenses[1], tmp_path, "right")
    sol = solve_pair(observations(ql, qr), (ml, mr), T_cad.inverse().rt(metres=True))
    rect = rectify.rectified_models(sol.models)
    epi = rectify.epipolar_stats(rectify.row_disparity(sol.models, rect, ql, qr))
    fl, fr = fisheye_check.read_fisheye(pl), fisheye_check.read_fisheye(pr)
    return sol, rect, epi, fisheye_check.cross_check(fl, fr, ql, qr, board_points(), sol.rt_right_left, rect, epi)


@pytest.mark.slow
def test_opencv_fisheye_agrees_with_ours_on_a_kannala_brandt_pair(kb_views, tmp_path):
    """Our pose (from the OPENCV8 fits) and OpenCV's (stereoCalibrate on the exact lenses) within 0.5 mm /
    0.03 deg of each other and of the truth; OpenCV's rectifying rotations agree with mrcal's on the
    baseline axis (< 0.01 deg) and differ only by a roll about it; the epipolar error through OpenCV's
    rectification and exact lenses at the noise, as ours."""
    from calibration.stereo.solve import pose_difference
    lenses, T_true, _, ql, qr = kb_views
    sol, _, epi, cc = _solve(kb_views, tmp_path)
    assert not cc["errors"], cc["errors"]
    ours = pose_difference(T_true, sol.T_left_right)
    assert ours["translation_mm"] < 1.0 and ours["rotation_deg"] < 0.05, ours
    assert cc["pose"]["translation_mm"] < 0.5 and cc["pose"]["rotation_deg"] < 0.03, cc["pose"]
    cv = Pose.from_rt(np.array(cc["pose"]["rt_right_left"]), metres=True).inverse()
    err_cv = pose_difference(T_true, cv)
    assert err_cv["translation_mm"] < 1.0 and err_cv["rotation_deg"] < 0.05, err_cv
    r = cc["rectification"]
    assert r["baseline_axis_deg"] < 0.01, r
    assert r["left_vs_right_difference_deg"] < 0.01, r     # one roll for both cameras: rows stay rows
    assert abs(abs(r["roll_about_baseline_deg"]) - r["rotation_left_deg"]) < 0.01, r
    rows = cc["epipolar_opencv_rectification"]["rows"]
    assert rows["n"] == epi["n"]
    assert 0.5 * NOISE_PX < rows["rms_px"] < 2.5 * NOISE_PX, rows
    assert rows["rms_px"] == pytest.approx(epi["rms_px"], rel=0.25)
    assert cc["epipolar_opencv_pose"]["rows"]["rms_px"] < 2.5 * NOISE_PX


@pytest.mark.slow
def test_cross_check_sees_a_wrong_pose(kb_views, tmp_path):
    """The check is not blind: our pose turned 0.1 deg about the left camera's x axis gives OpenCV's
    rectification rows 10x the noise apart, while OpenCV's own pose stays at the noise."""
    from calibration.stereo import fisheye_check, rectify
    lenses, _, _, ql, qr = kb_views
    sol, rect, epi, _ = _solve(kb_views, tmp_path)
    bad = Pose.from_rt(sol.rt_right_left, metres=True).inverse() @ Pose(rotvec_to_matrix(np.radians([0.1, 0, 0])),
                                                                        np.zeros(3))
    fl = fisheye_check.read_fisheye(tmp_path / "left_opencv.yaml")
    fr = fisheye_check.read_fisheye(tmp_path / "right_opencv.yaml")
    cc = fisheye_check.cross_check(fl, fr, ql, qr, board_points(), bad.inverse().rt(metres=True), rect, epi)
    assert cc["epipolar_opencv_rectification"]["rows"]["rms_px"] > 10 * NOISE_PX
    assert cc["epipolar_opencv_pose"]["rows"]["rms_px"] < 2.5 * NOISE_PX
    assert cc["pose"]["rotation_deg"] > 0.08


def test_a_file_that_is_not_a_fisheye_camera_is_named(tmp_path):
    from calibration.stereo.fisheye_check import FisheyeFileError, read_fisheye
    lens = truth_lens("kannala-brandt")
    _, p = lens.intrinsics()
    k = kb.KannalaBrandt(np.asarray(p, float), lens.size)
    path = tmp_path / "o8.yaml"
    path.write_text(formats.opencv_yaml(formats.representation(k, "rational_polynomial"), lens.size, camera_name="x"))
    with pytest.raises(FisheyeFileError, match=r"o8.yaml: distortion_model rational_polynomial, not fisheye"):
        read_fisheye(path)
    with pytest.raises(FisheyeFileError, match="no such file"):
        read_fisheye(tmp_path / "missing.yaml")


@pytest.mark.slow
def test_command_reports_the_cross_check_for_a_kannala_brandt_pair(kb_views, tmp_path, capsys):
    """`calibrate thermal-stereo` on 8 rendered pairs through the Kannala-Brandt lenses, the models in
    folders as `calibrate thermal --solver opencv` leaves them (thermal.cameramodel, thermal_opencv.yaml):
    the cross-check is found beside the models, in stereo.json and printed; OpenCV's pose and
    rectification agree with ours."""
    import json
    from calibration.stereo.solve import pose_difference
    lenses, T_true, _, _, _ = kb_views
    render_pairs(tmp_path, lenses, T_true)
    for side, lens in (("left", lenses[0]), ("right", lenses[1])):
        (tmp_path / side).mkdir()
        model, yaml_path = written_files(lens, tmp_path / side, side)
        model.write(str(tmp_path / side / "thermal.cameramodel"))
        yaml_path.rename(tmp_path / side / "thermal_opencv.yaml")
    out = tmp_path / "pair"
    code, stdout, err = run_cli(capsys, "--left", str(tmp_path / "left" / "thermal.cameramodel"), "--right",
                                str(tmp_path / "right" / "thermal.cameramodel"), "--images", str(tmp_path / "set"),
                                "--board", f"{BOARD[0]}x{BOARD[1]}", "--square", str(SQUARE), "--out", str(out))
    assert code == 0, err
    assert "cv2.fisheye cross-check: stereoRectify's rotations" in stdout
    rep = json.loads((out / "stereo.json").read_text())
    cc = rep["opencv_fisheye_cross_check"]
    assert not cc["errors"] and cc["files"][0].endswith("left/thermal_opencv.yaml")
    assert cc["pose"]["translation_mm"] < 0.5 and cc["pose"]["rotation_deg"] < 0.03, cc["pose"]
    assert cc["rectification"]["baseline_axis_deg"] < 0.01
    assert cc["epipolar_opencv_rectification"]["rows"]["rms_px"] == pytest.approx(rep["epipolar"]["rms_px"], rel=0.25)
    err_pose = pose_difference(T_true, Pose.from_rt(np.array(rep["rt_right_left"]), metres=True).inverse())
    assert err_pose["translation_mm"] < 1.0 and err_pose["rotation_deg"] < 0.05, err_pose


@pytest.mark.slow
def test_one_fisheye_flag_alone_is_one_line_exit_2(tmp_path, capsys):
    lens = truth_lens("kannala-brandt")
    model, yaml_path = written_files(lens, tmp_path, "left")
    model.write(str(tmp_path / "l.cameramodel"))
    code, _, err = run_cli(capsys, "--left", str(tmp_path / "l.cameramodel"), "--right", str(tmp_path / "l.cameramodel"),
                           "--images", str(tmp_path), "--board", "10x7", "--square", "0.04", "--out",
                           str(tmp_path / "o"), "--left-fisheye", str(yaml_path))
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and "--left-fisheye and --right-fisheye go together" in lines[0]
    assert not (tmp_path / "o").exists()
