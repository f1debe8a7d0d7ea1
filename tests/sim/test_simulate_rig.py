"""`platform_tools simulate-rig`: real MCAP with ROS 2 CDR messages, read back with the mcap
libraries; the injected offsets, drops, FFC freezes and clock step are in the data and in truth.json."""
from __future__ import annotations

import json
from collections import defaultdict

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

from platform_tools.sim.timeline import SimParams
from platform_tools.sim.writer import simulate


def read(path):
    out = defaultdict(list)
    with open(path, "rb") as f:
        for schema, channel, message, msg in make_reader(f, decoder_factories=[DecoderFactory()]) \
                .iter_decoded_messages():
            out[channel.topic].append((schema.name, message.log_time, msg))
    return out


def stamp(msg) -> int:
    return msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec


@pytest.fixture(scope="module")
def sim(tmp_path_factory, rig):
    out = tmp_path_factory.mktemp("sim") / "rec"
    truth = simulate(rig, out, SimParams(4.0, seed=3, drop_probability=0.02), scale=0.1)
    return rig, out, truth, read(out / "bag" / "bag_0.mcap")


@pytest.mark.slow
def test_every_rig_topic_with_its_ros_type(sim):
    rig, _, truth, msgs = sim
    t = rig.desc.on_device.topics
    types = {topic: {s for s, _, _ in v} for topic, v in msgs.items()}
    assert types[t.thermal_left] == {"sensor_msgs/msg/Image"}
    assert types[t.zed_left] == {"sensor_msgs/msg/CompressedImage"}
    assert types[t.zed_depth] == {"sensor_msgs/msg/Image"} and types[t.zed_imu] == {"sensor_msgs/msg/Imu"}
    assert types[t.thermal_right_status] == {"diagnostic_msgs/msg/DiagnosticArray"}
    img = msgs[t.thermal_left][0][2]
    rows = rig.desc.on_device.thermal_telemetry_rows      # Boson telemetry rows below the 64x51 image
    assert truth["telemetry"]["rows"] == rows == 2
    assert img.encoding == "mono16" and img.width == 64 and img.height == 51 + rows
    assert len(img.data) == 64 * (51 + rows) * 2
    assert img.header.frame_id == "thermal_left_optical"
    assert {k: len(v) for k, v in msgs.items()} == truth["topics"]


def test_frames_follow_the_trigger_with_the_injected_drops(sim):
    rig, _, truth, msgs = sim
    period_ns = 1e9 / rig.desc.sync.rate_hz
    stamps = np.array([stamp(m) for _, _, m in msgs[rig.desc.on_device.topics.thermal_left]])
    gaps = np.round(np.diff(stamps) / period_ns).astype(int)
    step = truth["clock_step"]["step_ns"] / period_ns
    missing = int(np.sum(gaps[np.abs(gaps - 1 - step) > 1] - 1))   # the clock step is not a drop
    assert missing == len(truth["dropped"]["thermal_left"]) > 0
    assert len(stamps) + missing == truth["triggers"]


def test_thermal_offset_after_the_zed_is_recoverable(sim):
    rig, _, truth, msgs = sim
    t = rig.desc.on_device.topics
    zed = np.array(sorted(stamp(m) for _, _, m in msgs[t.zed_left]))
    th = np.array(sorted(stamp(m) for _, _, m in msgs[t.thermal_right]))
    nearest = zed[np.clip(np.searchsorted(zed, th) - 1, 0, len(zed) - 1)]
    offset_ms = np.median(th - nearest) / 1e6
    assert offset_ms == pytest.approx(truth["offsets_ms"]["thermal_right"], abs=0.5)


def test_ffc_freezes_the_image_and_shows_in_the_status(sim):
    rig, _, truth, msgs = sim
    t = rig.desc.on_device.topics
    ffc = next(e for e in truth["ffc"] if e["camera"] == "thermal_left")
    tele = truth["telemetry"]["rows"] * 64 * 2
    frames = [(stamp(m), bytes(m.data)) for _, _, m in msgs[t.thermal_left]]
    during = [d for s, d in frames if ffc["start_ns"] <= s < ffc["end_ns"]]
    assert len(during) >= 10 and len({d[:-tele] for d in during}) == 1   # the image frozen for ~0.5 s
    assert len({d[-tele:] for d in during}) == len(during)               # the telemetry rows never are
    outside = [d for s, d in frames if s < ffc["start_ns"]]
    assert len(set(outside)) == len(outside)                          # live otherwise
    states = {kv.value for _, _, m in msgs[t.thermal_left_status] for kv in m.status[0].values
              if kv.key == "ffc_status"}
    assert {"0", "2", "3"} <= states


def test_the_clock_step_is_in_the_stamps(sim):
    rig, _, truth, msgs = sim
    imu = np.array([stamp(m) for _, _, m in msgs[rig.desc.on_device.topics.zed_imu]])
    d = np.diff(imu)
    big = d[d > 3 * np.median(d)]
    assert len(big) == 1 and big[0] - np.median(d) == pytest.approx(truth["clock_step"]["step_ns"], rel=0.01)


@pytest.mark.slow
def test_command_follows_the_trigger_rate(platform_tools, tmp_path):
    r = platform_tools("simulate-rig", "--out", str(tmp_path / "s"), "--duration", "2", "--scale", "0.05",
                       "--set", "sync.rate_hz=15", "--json")
    assert r.returncode == 0, r.stderr
    truth = json.loads((tmp_path / "s" / "truth.json").read_text())
    assert truth["triggers"] == 30 and truth["rate_hz"] == 15


@pytest.mark.slow
def test_bad_duration_is_one_line_exit_2(platform_tools, tmp_path):
    r = platform_tools("simulate-rig", "--out", str(tmp_path / "s"), "--duration", "0")
    assert r.returncode == 2 and "--duration" in r.stderr and not (tmp_path / "s").exists()


def test_telemetry_rows_agree_with_the_trigger_and_the_status_topic(sim):
    """The Bosons' telemetry: a counter of trigger pulses (dropped frames included), the FFC state the
    status topic publishes, and the counter at the start of the last FFC."""
    from platform_tools.boson.telemetry import decode_frame
    rig, _, truth, msgs = sim
    t = rig.desc.on_device.topics
    rows = truth["telemetry"]["rows"]
    period_ns = 1e9 / truth["rate_hz"]
    for cam in ("thermal_left", "thermal_right"):
        frames = [m for _, _, m in msgs[getattr(t, cam)]]
        tel = [decode_frame(np.frombuffer(m.data, "<u2").reshape(m.height, m.width), rows) for m in frames]
        counters = np.array([x.frame_counter for x in tel])
        assert np.all(np.diff(counters) >= 1)
        assert int(np.sum(np.diff(counters) - 1)) == len(truth["dropped"][cam])   # the drops, exactly
        base = truth["telemetry"]["frame_counter_base"][cam]
        assert counters[0] - base == next(k for k in range(10) if k not in truth["dropped"][cam])
        status = sorted((stamp(m), int(kv.value)) for _, _, m in msgs[getattr(t, f"{cam}_status")]
                        for kv in m.status[0].values if kv.key == "ffc_status")
        ffc = next(e for e in truth["ffc"] if e["camera"] == cam)
        start = truth["telemetry"]["ffc_start_pulse"][cam][0] + truth["telemetry"]["frame_counter_base"][cam]
        for m, x in zip(frames, tel):
            prior = [v for s, v in status if s <= stamp(m)]
            assert int(x.ffc_status) == prior[-1]                         # the state the status topic says
            if x.frame_counter >= start:
                assert x.ffc_frame == start and x.frames_since_ffc == x.frame_counter - start
        in_ffc = [stamp(m) for m, x in zip(frames, tel) if x.ffc_in_progress]
        assert abs(in_ffc[0] - ffc["start_ns"]) < 2 * period_ns and abs(in_ffc[-1] - ffc["end_ns"]) < 2 * period_ns


def test_thermal_counts_follow_the_synthetic_sensor_response(sim):
    """One temperature -> counts model for the project: the simulated Bosons' pixels are the scene's
    temperature through calibration.synth.sensor.counts, plus the simulator's noise of a few counts."""
    from calibration.synth.scene import AMBIENT_K
    from calibration.synth.sensor import COUNTS_PER_K, counts
    from platform_tools.sim import geometry
    rig, _, truth, msgs = sim
    scene, rows = truth["scene"], truth["telemetry"]["rows"]
    first = next(k for k in range(10) if k not in truth["dropped"]["thermal_left"])
    m = msgs[rig.desc.on_device.topics.thermal_left][0][2]
    raw = np.frombuffer(m.data, "<u2").reshape(m.height, m.width)[:m.height - rows].astype(float)
    renderer = geometry.SceneRenderer(rig, {k: tuple(v) for k, v in truth["image_sizes"].items()}, scene)
    r, boxes = renderer.render("thermal_left", first / truth["rate_hz"])
    t_k = geometry.temperature_c(r, boxes, scene) + geometry.ZERO_C_K
    noise = raw - counts(t_k - AMBIENT_K)
    assert abs(noise.mean()) < 2 and 4 < noise.std() < 12, (noise.mean(), noise.std())
    # and the contrast between the warm box and the sky is their temperature difference at the responsivity
    # (the box's checker adds 0 or 1 K)
    walker = next(b for b in boxes if b.name == "walker")
    on_walker, on_sky = r.which == boxes.index(walker), r.which == geometry.NO_HIT
    assert on_walker.sum() > 20 and on_sky.sum() > 20
    dt = walker.temperature_c - scene["sky_temperature_c"]
    gap = np.median(raw[on_walker]) - np.median(raw[on_sky])
    assert dt * COUNTS_PER_K - 60 < gap < (dt + 1) * COUNTS_PER_K + 60, gap
