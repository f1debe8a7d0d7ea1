"""Recordings in the released TartanRGBT stack's layout (issue 15 item 3), written by rosbags' writer
(tests/dataset/rosbags_rig.py) with the topics as upstream spells them: raw bgra8 ZED images with their factory
camera_info, Boson camera_info with the model of upstream's driver, std_msgs/Bool FFC status, no depth, and the
extra topics (heartbeat of a type outside any store, health, robot description, /diagnostics) a reader ignores.
The commands read them without flags: layout detected, camera_info used as the calibration, FFC windows from the
Bool status; bad input is one line, exit 2."""
from __future__ import annotations

import json

import numpy as np
import pytest
from rosbags.typesys import Stores, get_typestore

from platform_tools.cli.main import main
from tests.dataset import rosbags_rig

PERIOD_NS = rosbags_rig.PERIOD_NS
LIMITS = ["--set", "processing.sync_limits.max_drop_percent=10"]   # missing pulses count as drops
#: camera_info as a bag carries it (full-size images: the tiny recorded ones have the same aspect)
ZED_LEFT = dict(size=(1920, 1200), fx=733.5, fy=733.9, cx=961.2, cy=598.4, d=(-0.041, 0.013, 0.0002, -0.0003, -0.004))
THERMAL_LEFT = dict(size=(640, 512), fx=411.34, fy=412.67, cx=320.40, cy=251.97, d=(-0.3565, 0.1078, 0.0, 0.0, 0.0))
THERMAL_RIGHT = dict(size=(640, 512), fx=409.8, fy=410.1, cx=318.7, cy=254.2, d=(0.0, 0.0, 0.0, 0.0, 0.0))


def infos(topics: dict) -> dict:
    ts = get_typestore(Stores.ROS2_HUMBLE)
    out = {}
    for key, c, frame in (("zed_left_info", ZED_LEFT, "zed_left_camera_optical_frame"),
                          ("thermal_left_info", THERMAL_LEFT, "thermal_left_optical"),
                          ("thermal_right_info", THERMAL_RIGHT, "thermal_right_optical")):
        out[topics[key]] = rosbags_rig.camera_info(ts, rosbags_rig.T0_NS, frame, c["size"], c["fx"], c["fy"],
                                                   c["cx"], c["cy"], c["d"])
    return out


def upstream_bag(path, **spec):
    spec = rosbags_rig.Spec(**({"status": "bool", "zed_compressed": False, "depth": False, "extra": True,
                                "seed": 3} | spec))
    truth = rosbags_rig.write(path, spec, rosbags_rig.UPSTREAM, infos=infos(rosbags_rig.UPSTREAM))
    return path, truth


def run(capsys, *argv):
    code = main(list(argv))
    cap = capsys.readouterr()
    return code, cap.out, cap.err


@pytest.fixture(scope="module")
def upstream(tmp_path_factory):
    return upstream_bag(tmp_path_factory.mktemp("up") / "bag")


def stamps_of(truth, cam, triggers):
    return sorted(t for t, k in truth["trigger_of"][cam].items() if k in triggers)


@pytest.mark.slow
def test_upstream_layout_is_read_without_flags(upstream, capsys):
    bag, truth = upstream
    code, out, err = run(capsys, "sync-check", str(bag), "--json", *LIMITS)
    assert code == 0, err
    rep = json.loads(out)
    assert rep["layout"] == "tartanrgbt" and rep["depth"] is None
    assert rep["streams"]["thermal_left"]["topic"] == "/thermal_left/image"
    assert rep["streams"]["zed_left"]["frames"] == len(truth["trigger_of"]["zed_left"])
    assert rep["streams"]["thermal_right"]["frames"] == len(truth["trigger_of"]["thermal_right"])
    # the Bool status: one FFC on the left, from its first frozen frame to the first frame after it (exactly:
    # a Bool is stamped with the frame it follows); none on the right, and /diagnostics' ffc_status ignored
    ffc = truth["ffc_triggers"]["thermal_left"]
    frames = sorted(truth["trigger_of"]["thermal_left"].items())
    first_after = next(t for t, k in frames if k > max(ffc))
    (period,) = rep["ffc"]["thermal_left"]
    assert period["source"] == "status"
    assert period["start_ns"] == stamps_of(truth, "thermal_left", ffc)[0] and period["end_ns"] == first_after
    assert rep["ffc"]["thermal_right"] == []
    for cam, lat in truth["latency_ms"].items():
        (seg,) = rep["triggers"][cam]["segments"]
        assert abs(seg["offset_ms"] - lat) < 0.5, (cam, seg)


@pytest.mark.slow
def test_camera_info_is_the_calibration(upstream, capsys, rig):
    from platform_tools.rig.nominal import nominal_cameras
    bag, _ = upstream
    code, out, err = run(capsys, "sync-check", str(bag), "--json", *LIMITS)
    assert code == 0, err
    cal = json.loads(out)["calibration"]
    assert cal["source"].startswith("camera_info (zed_left, thermal_left, thermal_right; extrinsics nominal)")
    cams = cal["cameras"]
    for frame, c, lens in (("zed_x_left_optical", ZED_LEFT, "LENSMODEL_OPENCV5"),
                           ("thermal_left_optical", THERMAL_LEFT, "LENSMODEL_OPENCV5"),
                           ("thermal_right_optical", THERMAL_RIGHT, "LENSMODEL_PINHOLE")):
        m = cams[frame]
        want = [c["fx"], c["fy"], c["cx"], c["cy"]] + (list(c["d"]) if lens != "LENSMODEL_PINHOLE" else [])
        assert m["lensmodel"] == lens and m["imagersize"] == list(c["size"])
        assert np.allclose(m["intrinsics"], want, rtol=0, atol=1e-9), (frame, m["intrinsics"])
        nominal = nominal_cameras(rig)[frame]
        assert np.allclose(m["rt_cam_ref"], nominal.extrinsics_rt_fromref(), atol=1e-12)
        assert not np.isclose(nominal.intrinsics()[1][0], c["fx"])      # not the nominal model
    code, out, _ = run(capsys, "sync-check", str(bag), *LIMITS)
    assert code == 0 and "layout tartanrgbt; calibration: camera_info (" in out and "no depth topic" in out


@pytest.mark.slow
def test_calibration_option_overrides_camera_info(upstream, capsys, rig, tmp_path):
    from platform_tools.dataset.calib import FILES
    from platform_tools.rig.nominal import nominal_cameras
    bag, _ = upstream
    for frame, m in nominal_cameras(rig).items():
        if frame in FILES:
            m.write(str(tmp_path / FILES[frame]))
    code, out, err = run(capsys, "sync-check", str(bag), "--json", "--calibration", str(tmp_path), *LIMITS)
    assert code == 0, err
    cal = json.loads(out)["calibration"]
    assert cal["source"] == str(tmp_path)
    fx = cal["cameras"]["thermal_left_optical"]["intrinsics"][0]
    assert fx == pytest.approx(nominal_cameras(rig)["thermal_left_optical"].intrinsics()[1][0])


@pytest.mark.slow
def test_export_without_depth_is_refused_in_one_line(upstream, capsys, tmp_path):
    bag, _ = upstream
    code, out, err = run(capsys, "export", str(bag), "--out", str(tmp_path / "ds"), *LIMITS, "--depth", "recorded")
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert str(bag) in err and "no zed_depth" in err and "tartanrgbt layout" in err, err
    assert "needs the ZED depth" in err and "--topics" in err and "--depth stereo" in err, err
    assert not (tmp_path / "ds").exists()


@pytest.mark.slow
def test_unexpected_status_type_is_one_line(tmp_path, capsys):
    bag, _ = upstream_bag(tmp_path / "bag", status="uint8", extra=False, triggers=40, missing=(), ffc={})
    for cmd in (["sync-check", str(bag)], ["export", str(bag), "--out", str(tmp_path / "ds")]):
        code, out, err = run(capsys, *cmd)
        assert code == 2 and len(err.strip().splitlines()) == 1, err
        assert ".mcap" in err and "/thermal_left/ffc_status" in err and "std_msgs/msg/UInt8" in err, err
        assert "std_msgs/msg/Bool" in err and "Traceback" not in err
    assert not (tmp_path / "ds").exists()


@pytest.mark.slow
def test_unknown_layout_is_one_line(tmp_path, capsys):
    topics = {k: "/cam" + v for k, v in rosbags_rig.UPSTREAM.items()}
    rosbags_rig.write(tmp_path / "bag", rosbags_rig.Spec(triggers=20, missing=(), ffc={}, status=None, depth=False,
                                                         zed_compressed=False), topics)
    code, out, err = run(capsys, "sync-check", str(tmp_path / "bag"))
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert str(tmp_path / "bag") in err and "unknown topic layout" in err and "/cam/thermal_left/image" in err, err
    assert "--topics" in err


@pytest.mark.slow
def test_topic_map_with_depth_exports_with_camera_info(tmp_path, capsys):
    """A bag in a third layout, given by a topic map: its camera_info is the calibration of the export."""
    topics = {k: "/rig" + v for k, v in rosbags_rig.UPSTREAM.items()} | {"zed_depth": "/rig/zed/depth"}
    spec = rosbags_rig.Spec(triggers=60, missing=(20,), ffc={}, status="bool", zed_compressed=False, seed=4)
    truth = rosbags_rig.write(tmp_path / "bag", spec, topics, infos=infos(topics))
    tmap = tmp_path / "topics.yaml"
    tmap.write_text("".join(f"{k}: {v}\n" for k, v in topics.items() if k != "zed_right_info"))
    code, out, err = run(capsys, "sync-check", str(tmp_path / "bag"))
    assert code == 2 and "unknown topic layout" in err                   # not detected without the map
    code, out, err = run(capsys, "export", str(tmp_path / "bag"), "--out", str(tmp_path / "ds"), "--rate", "30",
                         "--topics", str(tmap), *LIMITS)
    assert code == 0, err
    assert f"layout {tmap}; depth recorded; calibration: camera_info (zed_left, thermal_left, thermal_right" in out
    manifest = json.loads((tmp_path / "ds" / "export.json").read_text())
    assert manifest["recordings"][0]["layout"] == str(tmap)
    m = manifest["calibration_models"]["cameras"]["thermal_left_optical"]
    c = THERMAL_LEFT
    assert m["lensmodel"] == "LENSMODEL_OPENCV5"
    assert np.allclose(m["intrinsics"], [c["fx"], c["fy"], c["cx"], c["cy"], *c["d"]], atol=1e-9)
    rows = (tmp_path / "ds" / "index.csv").read_text().splitlines()
    assert len(rows) - 1 >= 0.8 * len(truth["trigger_of"]["thermal_left"])
    assert rows[1].count("camera_info (") >= 1


@pytest.mark.slow
@pytest.mark.parametrize("text, words", [
    ("thermal_left: /a\nthermal_right: /b\nzed_left: /c\nzed_centre: /d\n", ["unknown stream name 'zed_centre'"]),
    ("thermal_left: /a\nthermal_right: b\nzed_left: /c\n", ["thermal_right", "not a topic name"]),
    ("thermal_left: /a\nzed_left: /c\n", ["no thermal_right topic"]),
    ("- /a\n", ["a topic map is a mapping"])])
def test_bad_topic_map_is_one_line(tmp_path, capsys, text, words):
    f = tmp_path / "map.yaml"
    f.write_text(text)
    code, out, err = run(capsys, "sync-check", str(tmp_path), "--topics", str(f))
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert str(f) in err and all(w in err for w in words), err
