"""A recording without the thermal status topic (as when the status publisher did not run): the FFC
windows still come from the Boson telemetry rows of the thermal frames, for sync-check and export."""
from __future__ import annotations

import json
import shutil

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap.writer import Writer

from platform_tools.dataset.pairing import plan
from platform_tools.dataset.recording import open_recording
from platform_tools.dataset.sync import Limits, analyse


def without_status(src, dst, rig) -> None:
    """Copy a simulated recording, dropping every message of the thermal status topics."""
    t = rig.desc.on_device.topics
    drop = {t.thermal_left_status, t.thermal_right_status}
    shutil.copytree(src, dst)
    bag = dst / "bag" / "bag_0.mcap"
    with open(src / "bag" / "bag_0.mcap", "rb") as fin, open(bag, "wb") as fout:
        reader = make_reader(fin)
        w = Writer(fout)
        w.start(profile="ros2", library="test")
        schemas, channels = {}, {}
        for schema, channel, msg in reader.iter_messages(log_time_order=True):
            if channel.topic in drop:
                continue
            if schema.id not in schemas:
                schemas[schema.id] = w.register_schema(schema.name, schema.encoding, schema.data)
            if channel.id not in channels:
                channels[channel.id] = w.register_channel(channel.topic, channel.message_encoding,
                                                          schemas[schema.id], channel.metadata)
            w.add_message(channels[channel.id], msg.log_time, msg.data, msg.publish_time, msg.sequence)
        w.finish()


@pytest.fixture(scope="module")
def no_status(sim, rig, tmp_path_factory):
    dst = tmp_path_factory.mktemp("nostatus") / "rec"
    without_status(sim[0], dst, rig)
    return dst, sim[1]


def test_ffc_windows_from_the_telemetry_rows(no_status, rig):
    path, truth = no_status
    rec = open_recording(path, rig)
    assert rec.status_source == {"thermal_left": "telemetry", "thermal_right": "telemetry"}
    period = 1e9 / truth["rate_hz"]
    rep = analyse(rec, rig, Limits.from_rig(rig))
    for e in truth["ffc"]:
        (got,) = rep["ffc"][e["camera"]]
        assert got["source"] == "telemetry"
        # per frame: the first frame captured in the window (the Boson's trigger offset later) and
        # the first one after it
        assert 0 <= got["start_ns"] - e["start_ns"] < period + 15e6
        assert 0 <= got["end_ns"] - e["end_ns"] < period + 15e6


def test_the_status_topic_wins_when_present(sim, rig):
    rec = open_recording(sim[0], rig)
    assert rec.status_source == {"thermal_left": "status", "thermal_right": "status"}


def test_export_plan_flags_the_ffc_frames_without_the_status_topic(no_status, rig):
    path, truth = no_status
    rec = open_recording(path, rig)
    pl = plan(rec, rig, rate_hz=30.0, tolerance_ms=rig.desc.processing.pair_tolerance_ms, ffc_margin=0,
              keep_ffc=True)
    period = 1e9 / truth["rate_hz"]
    checked = 0
    for p in pl.pairs:
        for cam in ("thermal_left", "thermal_right"):
            t = p.frames[cam]["stamp_ns"]
            e = next(e for e in truth["ffc"] if e["camera"] == cam)
            if e["start_ns"] + period <= t < e["end_ns"] - period:
                assert p.ffc[cam] and p.ffc_status[cam] == 2
                checked += 1
            elif t < e["start_ns"] - period or t > e["end_ns"] + 2 * period:
                assert not p.ffc[cam] and p.ffc_status[cam] in (0, 3)
    assert checked >= 10
    assert pl.counts["ffc_dropped"] == 0   # keep_ffc


@pytest.mark.slow
def test_sync_check_command_without_the_status_topic(platform_tools, no_status):
    path, truth = no_status
    r = platform_tools("sync-check", str(path), "--json")
    doc = json.loads(r.stdout)
    assert {p["source"] for c in ("thermal_left", "thermal_right") for p in doc["ffc"][c]} == {"telemetry"}
    assert np.all([len(doc["ffc"][c]) == 1 for c in ("thermal_left", "thermal_right")])


@pytest.mark.slow
def test_the_frame_counter_of_the_telemetry_rows_tells_host_drops_from_missing_pulses(sim, rig):
    """The simulator's Bosons count every trigger pulse (truth.json: frame_counter_base + pulse number); the frames
    it dropped on the host show as counter gaps, and no pulse is missing."""
    path, truth = sim
    rec = open_recording(path, rig)
    rep = analyse(rec, rig, Limits.from_rig(rig))
    for cam in ("thermal_left", "thermal_right"):
        st = rec.streams[cam]
        base = truth["telemetry"]["frame_counter_base"][cam]
        first, last = int(st.counter.min()) - base, int(st.counter.max()) - base
        dropped = [k for k in truth["dropped"][cam] if first < k < last]
        assert rep["triggers"][cam]["frame_counter"] == {"host_drops": len(dropped), "missing_pulses": 0,
                                                         "repeated_frames": 0}
        assert len(dropped) > 0
        # the clock step of every stream is sized by the counter on the thermal clock
        (step,) = rep["triggers"][cam]["clock_steps"]
        assert step["sized_by"] == "frame counter"
        assert step["step_ms"] == pytest.approx(truth["clock_step"]["step_ns"] / 1e6, abs=1.0)
