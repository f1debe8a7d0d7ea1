"""Image-motion correlation as the last resort of the pairing (platform_tools/dataset/motion.py).

The pure functions are checked on signals made here. The commands run on bags written by rosbags
(``write_scene`` below: the stamps of tests/dataset/rosbags_rig.timeline, images rendered here) where a bright
blob moves in jerks and is drawn into the ZED left/right and both thermal images at its position at the true
trigger of each frame. No pulse is missing (no common trigger gaps), no telemetry (no frame counter), no stated
latency (``sync.stamp_latency_ms={}``): only the motion can tell which trigger a thermal frame belongs to."""
from __future__ import annotations

import csv
import json
from pathlib import Path

import cv2
import numpy as np
import pytest
from rosbags.rosbag2 import Writer
from rosbags.typesys import Stores, get_typestore

from platform_tools.cli.main import main
from platform_tools.dataset import motion
from tests.dataset import rosbags_rig

ZED_SIZE = (96, 60)        # W, H: 1920x1200 / 20
THERMAL_SIZE = (80, 64)    # 640x512 / 8
NO_WINDOW = ["--set", "sync.stamp_latency_ms={}", "--set", "processing.sync_limits.max_drop_percent=10"]
LATE = {"thermal_left": 40.0, "thermal_right": 75.0}


# ----------------------------------------------------------------------------- pure functions
def test_the_signal_is_the_mean_difference_of_consecutive_triggers_only():
    frames = np.zeros((5, 2, 2))
    frames[1] += 4.0            # trigger 11: 4 brighter than 10
    frames[3] += 1.0            # trigger 14 (13 is missing): not consecutive with 11
    frames[4] += 3.0            # trigger 15: 2 brighter than 14
    k, s = motion.motion_signal(frames, np.array([10, 11, 12, 14, 15]))
    assert k.tolist() == [11, 12, 15] and s.tolist() == [4.0, 4.0, 2.0]
    k, s = motion.motion_signal(frames, np.array([10, 11, 12, 14, 15]), np.array([1, 1, 0, 1, 1], bool))
    assert k.tolist() == [11, 15]       # a frozen frame gives no sample, before or after it


def test_downsample_block_averages_to_the_width():
    img = np.arange(128 * 4 * 3, dtype=np.uint8).reshape(4, 128, 3)
    small = motion.downsample(img, 64)
    assert small.shape == (2, 64)
    assert small[0, 0] == pytest.approx(img[:2, :2].mean())


def jerky(rng, n):
    """A motion signal: still half the time, jerks of random size otherwise (image units)."""
    return 1.0 + np.where(rng.random(n) < 0.5, 0.0, rng.uniform(2, 20, n)) + rng.normal(0, 0.05, n)


def test_the_candidate_that_lines_the_motion_up_is_chosen():
    rng = np.random.default_rng(1)
    zk = np.arange(200)
    z = jerky(rng, 200)
    tk = zk + 3                                   # base = trigger + 3
    t = 500 * z + rng.normal(0, 30, 200)          # another camera, other units
    d = motion.decide(zk, z, tk, t, {n: 6.7 + 33.3 * n for n in range(0, 6)})
    assert d.n == 3 and d.report["best_r"] > 0.9 and d.report["best_r"] - d.report["runner_up_r"] >= 0.3


def test_a_still_scene_is_too_little_motion():
    rng = np.random.default_rng(2)
    zk = np.arange(200)
    d = motion.decide(zk, 1 + rng.normal(0, 0.02, 200), zk + 1, 30 + rng.normal(0, 1, 200), {0: 6.7, 1: 40.0})
    assert d.n is None and "too little motion" in d.text and d.report["zed_moving"] < motion.MIN_MOVING


def test_smooth_motion_has_no_clear_peak():
    """Speed changing over many frames: the offsets one trigger apart correlate nearly as well: refused."""
    zk = np.arange(300)
    z = 2 + np.sin(zk / 15.0) + (zk % 60 > 30)
    z = np.convolve(z, np.ones(9) / 9, mode="same")
    d = motion.decide(zk, z, zk + 2, 10 * z, {n: 6.7 + 33.3 * n for n in range(0, 5)})
    assert d.n is None and "no clear correlation peak" in d.text
    assert d.report["best_ms"] == pytest.approx(6.7 + 66.6)      # the peak is there, only not clear


def test_windows_are_bounded_and_spread():
    assert motion.windows(0, 100) == [(0, 100)]
    w = motion.windows(0, 999)
    assert len(w) == motion.WINDOWS and w[0][0] == 0 and w[-1][1] == 999
    assert all(b - a + 1 == motion.WINDOW_TRIGGERS for a, b in w)


# ----------------------------------------------------------------------------- bags with a moving scene
def blob_path(n: int, seed: int, still: bool) -> np.ndarray:
    """(n, 2) blob centre per trigger, in [0.15, 0.85] of the image: jerks of random size (half the triggers
    still), reflected at the edges; a fixed point when ``still``."""
    rng = np.random.default_rng(seed + 7)
    if still:
        return np.full((n, 2), 0.5)
    step = np.where(rng.random((n, 1)) < 0.5, 0.0, rng.uniform(-0.12, 0.12, (n, 2)))
    p = 0.5 + np.cumsum(step, axis=0)
    p = 0.15 + np.abs(np.mod(p - 0.15, 1.4) - 0.7)            # reflect into [0.15, 0.85]
    return p


def render(size, centre, background, peak, sigma_frac=0.08) -> np.ndarray:
    w, h = size
    y, x = np.mgrid[0:h, 0:w]
    s = sigma_frac * w
    return background + peak * np.exp(-((x - centre[0] * w) ** 2 + (y - centre[1] * h) ** 2) / (2 * s * s))


def write_scene(path: Path, spec: rosbags_rig.Spec, topics: dict, still: bool = False) -> dict:
    """A bag like rosbags_rig.write's (same timeline), but the images show the blob at its position at each frame's
    true trigger; returns the truth (per stream, host stamp -> trigger; the FFC triggers)."""
    ts = get_typestore(Stores.ROS2_HUMBLE)
    rng = np.random.default_rng(spec.seed + 100)
    tl = rosbags_rig.timeline(spec)
    where = blob_path(spec.triggers, spec.seed, still)
    zbg = rng.uniform(40, 90, (ZED_SIZE[1], ZED_SIZE[0]))
    tbg = 20000 + rng.normal(0, 150, (THERMAL_SIZE[1], THERMAL_SIZE[0]))
    msgs, truth = [], {"trigger_of": {}, "ffc_triggers": {}}
    kz, tz, hz = tl["zed_left"]
    for k, t, h in zip(kz, tz, hz):
        log = int(t) + rosbags_rig.TRANSPORT_NS
        for side in ("left", "right"):
            grey = np.clip(render(ZED_SIZE, where[k], zbg, 150) + rng.normal(0, 2, zbg.shape), 0, 255)
            bgr = np.repeat(grey.astype(np.uint8)[..., None], 3, axis=2)
            m = ts.types["sensor_msgs/msg/CompressedImage"](
                header=rosbags_rig._header(ts, int(h), f"zed_{side}_camera_optical_frame"), format="jpeg",
                data=cv2.imencode(".jpg", bgr)[1].reshape(-1))
            msgs.append((log, topics[f"zed_{side}"], "sensor_msgs/msg/CompressedImage", m))
        msgs.append((log, topics["zed_depth"], "sensor_msgs/msg/Image",
                     rosbags_rig._image(ts, int(h), "zed_left_camera_optical_frame",
                                        np.full((ZED_SIZE[1], ZED_SIZE[0]), 3.0, np.float32), "32FC1")))
        for s in ("zed_left", "zed_right", "zed_depth"):
            truth["trigger_of"].setdefault(s, {})[int(h)] = int(k)
    for cam in ("thermal_left", "thermal_right"):
        k_, t_, h_ = tl[cam]
        first, last = spec.ffc.get(cam, (-1, -2))
        truth["ffc_triggers"][cam] = [int(k) for k in k_ if first <= k <= last]
        px = None
        for k, t, h in zip(k_, t_, h_):
            if not (first <= k <= last and px is not None):      # an FFC freezes the frame before it
                img = render(THERMAL_SIZE, where[k], tbg, 3000) + rng.normal(0, 30, tbg.shape)
                px = np.clip(img, 0, 65535).astype(np.uint16)
            msgs.append((int(t) + rosbags_rig.TRANSPORT_NS, topics[cam], "sensor_msgs/msg/Image",
                         rosbags_rig._image(ts, int(h), f"{cam}_optical", px, "mono16")))
            truth["trigger_of"].setdefault(cam, {})[int(h)] = int(k)
    msgs.sort(key=lambda m: m[0])
    with Writer(path, version=8, storage_plugin=rosbags_rig.StoragePlugin.MCAP) as w:
        conns = {}
        for log, topic, typ, msg in msgs:
            if topic not in conns:
                conns[topic] = w.add_connection(topic, typ, typestore=ts)
            w.write(conns[topic], log, ts.serialize_cdr(msg, typ))
    return truth


def scene_spec(seed: int) -> rosbags_rig.Spec:
    """40 / 75 ms late, no missing pulse (no common gaps), 2 % host drops, an FFC freeze on the left, no status
    topic, no telemetry, no IMU."""
    return rosbags_rig.Spec(latency_ms=dict(LATE), missing=(), status=None, imu=False, seed=seed)


def run(capsys, *argv):
    code = main(list(argv))
    cap = capsys.readouterr()
    return code, cap.out, cap.err


@pytest.mark.slow
def test_a_moving_scene_decides_the_offset_and_every_pair_is_right(tmp_path, capsys, rig):
    bag = tmp_path / "moving"
    truth = write_scene(bag, scene_spec(seed=4), rosbags_rig.project_layout(rig))
    code, out, err = run(capsys, "sync-check", str(bag), "--json", *NO_WINDOW)
    assert code == 0, err
    rep = json.loads(out)
    for cam, late in LATE.items():
        (seg,) = rep["triggers"][cam]["segments"]
        assert seg["offset_ms"] == pytest.approx(late, abs=0.5)
        assert seg["established_by"].startswith("image motion correlation"), seg["established_by"]
        m = seg["motion"]
        assert m["best_ms"] == pytest.approx(late, abs=0.5)
        assert m["best_r"] - m["runner_up_r"] >= motion.MIN_MARGIN and m["zed_moving"] >= motion.MIN_MOVING
    code, out, _ = run(capsys, "sync-check", str(bag), *NO_WINDOW)
    assert code == 0 and "(image motion correlation" in out

    ds = tmp_path / "ds"
    code, out, err = run(capsys, "export", str(bag), "--out", str(ds), "--rate", "30", *NO_WINDOW)
    assert code == 0, err
    of = truth["trigger_of"]
    rows = list(csv.DictReader((ds / "index.csv").open()))
    exported = []
    for r in rows:
        k = of["zed_left"][int(r["t_zed_left_ns"])]
        for s in ("zed_right", "zed_depth", "thermal_left", "thermal_right"):
            assert of[s][int(r[f"t_{s}_ns"])] == k, (s, r)          # the frame of the same trigger pulse
        exported.append(k)
    complete = set(of["zed_left"].values()) & set(of["thermal_left"].values()) & set(of["thermal_right"].values())
    assert len(set(exported)) == len(exported) and set(exported) <= complete
    assert not set(exported) & set(truth["ffc_triggers"]["thermal_left"])
    assert len(exported) > 90


@pytest.mark.slow
def test_a_still_scene_stays_ambiguous_and_says_the_motion_was_insufficient(tmp_path, capsys, rig):
    bag = tmp_path / "still"
    write_scene(bag, scene_spec(seed=4), rosbags_rig.project_layout(rig), still=True)
    code, out, err = run(capsys, "sync-check", str(bag), *NO_WINDOW)
    (fail,) = [line for line in out.splitlines() if line.startswith("FAIL trigger of every thermal frame")]
    assert code == 1, err
    assert "ambiguous" in fail and "no stated latency" in fail
    assert "image motion insufficient: the scene had too little motion" in fail
    ds = tmp_path / "ds"
    code, _, err = run(capsys, "export", str(bag), "--out", str(ds), "--rate", "30", *NO_WINDOW)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and "too little motion" in lines[0] and str(bag) in lines[0]
    assert not ds.exists()


@pytest.mark.slow
def test_a_long_recording_is_decided_from_a_bounded_read_and_every_frame_gets_its_trigger(tmp_path):
    """600 triggers (20 s): the motion is read in WINDOWS windows of WINDOW_TRIGGERS triggers, not whole, and every
    thermal frame is assigned the trigger pulse that exposed it."""
    from platform_tools.dataset import sync
    from platform_tools.dataset.recording import open_recording
    from platform_tools.rig.loader import load_rig
    from platform_tools.dataset.trigger import MAX_PERIODS
    rig = load_rig(overrides=["sync.stamp_latency_ms={}"])
    spec = scene_spec(seed=9)
    spec.triggers = 600
    bag = tmp_path / "long"
    truth = write_scene(bag, spec, rosbags_rig.project_layout(rig))
    rec = open_recording(bag, rig)
    a = sync.triggers(rec, rig)
    kz = {int(t): int(k) for t, k in zip(rec.streams["zed_left"].stamp_ns, a.reference.trigger)}
    for cam, late in LATE.items():
        (seg,) = a.cameras[cam].segments
        assert seg.offset_ns / 1e6 == pytest.approx(late, abs=0.5) and seg.established_by.startswith("image motion")
        read = seg.motion["frames_read"]
        assert read[cam] <= motion.WINDOWS * motion.WINDOW_TRIGGERS < len(rec.streams[cam].stamp_ns) / 2
        assert read["zed_left"] <= motion.WINDOWS * (motion.WINDOW_TRIGGERS + MAX_PERIODS + 3)
        # the ZED numbering of the truth: the trigger of the ZED frame of the same pulse
        zed_number = {truth["trigger_of"]["zed_left"][t]: k for t, k in kz.items()}
        for t, k in zip(rec.streams[cam].stamp_ns, a.cameras[cam].trigger):
            pulse = truth["trigger_of"][cam][int(t)]
            if pulse in zed_number:
                assert k == zed_number[pulse], (cam, pulse)
