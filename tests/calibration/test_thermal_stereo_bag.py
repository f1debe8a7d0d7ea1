"""`calibrate thermal-stereo --bag REC` on a recording written by the rosbags library (tests/dataset/rosbags_rig.py,
not this project's simulator or recorder): 8 stereo views of a board through two stereographic truth lenses at a known
pose (tests/calibration/test_thermal_stereo.py's renderer), a different view at each trigger, the right Boson stamped
26 ms later than the left (USB buffering): nearest stamps would pair each right frame with the next trigger's left
one, a different board pose. The pairs are taken by trigger."""
from __future__ import annotations

import json

import cv2
import mrcal
import numpy as np
import pytest

from calibration.synth.truth_files import write_cameramodel
from platform_tools.rig.frames import Pose
from tests.calibration.test_thermal_stereo import SQUARE, cad_pose, render_pairs, run_cli, truth_lenses, truth_pose
from tests.dataset import rosbags_rig

pytestmark = pytest.mark.slow          # 8 rendered pairs, a 40-trigger bag with 640x512 thermal frames
VIEWS = 8
LATENCY_MS = {"thermal_left": 2.0, "thermal_right": 28.0}       # within the rig's 0..30 ms windows


@pytest.fixture(scope="module")
def bag(tmp_path_factory, rig):
    windows = rig.desc.sync.stamp_latency_ms      # the latencies must be ones the trigger assignment accepts
    assert all(windows[c].min.value <= ms <= windows[c].max.value for c, ms in LATENCY_MS.items())
    root = tmp_path_factory.mktemp("stereobag")
    lenses = truth_lenses()
    T_true = truth_pose(cad_pose())
    render_pairs(root, lenses, T_true, n=VIEWS)
    px = {cam: [cv2.imread(str(root / "set" / side / f"{k:03d}.png"), cv2.IMREAD_UNCHANGED) for k in range(VIEWS)]
          for cam, side in (("thermal_left", "left"), ("thermal_right", "right"))}
    assert px["thermal_left"][0].dtype == np.uint16
    for side, lens in (("left", lenses[0]), ("right", lenses[1])):
        write_cameramodel(root / f"{side}.cameramodel", lens, f"truth lens of the {side} camera")
    spec = rosbags_rig.Spec(triggers=40, missing=(), drop=0.0, ffc={}, latency_ms=dict(LATENCY_MS), seed=6,
                            thermal_px={cam: (lambda k, imgs=imgs: imgs[k % VIEWS]) for cam, imgs in px.items()})
    truth = rosbags_rig.write(root / "bag", spec, rosbags_rig.project_layout(rig))
    return root, T_true, truth


def test_the_pairs_are_those_of_one_trigger_and_the_pose_is_found(bag, tmp_path, capsys):
    root, T_true, truth = bag
    out = tmp_path / "pair"
    code, stdout, err = run_cli(capsys, "--left", str(root / "left.cameramodel"), "--right",
                                str(root / "right.cameramodel"), "--bag", str(root / "bag"), "--board", "10x7",
                                "--square", str(SQUARE), "--out", str(out), "--json", "-q")
    assert code == 0, err
    rep = json.loads(stdout)
    frames = rep["bag_frames"]
    assert frames["paired_by"] == "trigger" and frames["pairs"] == 40 and frames["chosen"] >= 5
    left_stamps = np.array(sorted(truth["trigger_of"]["thermal_left"]))
    for name, (tl, tr) in frames["chosen_stamps_ns"].items():
        assert truth["trigger_of"]["thermal_left"][tl] == truth["trigger_of"]["thermal_right"][tr], name
        nearest = left_stamps[np.argmin(np.abs(left_stamps - tr))]
        assert nearest != tl            # the case this is for: the nearest stamp is the next trigger's frame
    assert rep["shared_views"] == frames["chosen"] and rep["images"] is None
    R = mrcal.cameramodel(str(out / "right.cameramodel"))
    T = Pose.from_rt(R.extrinsics_rt_fromref(), metres=True).inverse()
    D = T_true.inverse() @ T
    assert np.linalg.norm(T.t - T_true.t) < 1.0 and D.angle_deg() < 0.05, (T.t, T_true.t, D.angle_deg())
    assert rep["epipolar"]["rms_px"] < 0.1


def test_a_recording_without_the_zed_is_one_line(bag, tmp_path, capsys):
    from tests.calibration.test_thermal_bag import _write_bag
    root, _, _ = bag
    img = cv2.imread(str(root / "set" / "left" / "000.png"), cv2.IMREAD_UNCHANGED)
    _write_bag(tmp_path / "thermal_only", [(img, False)] * 3)
    out = tmp_path / "pair"
    code, _, err = run_cli(capsys, "--left", str(root / "left.cameramodel"), "--right", str(root / "right.cameramodel"),
                           "--bag", str(tmp_path / "thermal_only"), "--board", "10x7", "--square", str(SQUARE),
                           "--out", str(out), "-q")
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "--bag" in err and not out.exists()


def test_images_and_bag_together_are_refused(bag, tmp_path, capsys):
    root, _, _ = bag
    with pytest.raises(SystemExit) as e:
        run_cli(capsys, "--left", str(root / "left.cameramodel"), "--right", str(root / "right.cameramodel"),
                "--bag", str(root / "bag"), "--images", str(root / "set"), "--board", "10x7", "--square", "0.04",
                "--out", str(tmp_path / "x"))
    assert e.value.code == 2
