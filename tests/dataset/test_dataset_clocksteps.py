"""Clock steps on one clock, known from the stamps only modulo a trigger period, on recordings written by rosbags'
writer (tests/dataset/rosbags_rig.py) and then re-timed here as a recorder would log them: every message's log
time is its receive time on the recorder's clock (transport jitter drawn here: ZED |N(0, 2 ms)|, Boson a gamma
tail of mean 3 ms), and that clock follows the host's forward steps (a recorder on CLOCK_REALTIME) or none. A step
on one Boson's clock only is written here into that camera's header stamps. No IMU: the stamps alone leave every
step modulo a period; the recorder's log times (platform_tools/dataset/clocksteps.py) must size it, and every
exported pair is checked against the trigger pulse the writer recorded for each frame."""
from __future__ import annotations

import csv
import json
import struct
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from rosbags.rosbag2 import Reader, StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

from platform_tools.dataset import clocksteps, sync, trigger
from platform_tools.dataset.recording import open_recording
from tests.dataset import rosbags_rig
from tests.dataset.test_dataset_rosbags_pairing import LIMITS, check_pairs, run

P = rosbags_rig.PERIOD_NS
#: CLOCK_REALTIME - CLOCK_MONOTONIC when usb_cam started (an Orin booted about 1.7e9 s after the epoch)
REALTIME_MINUS_MONO = 1_699_999_000 * 1_000_000_000


def _stamp(raw: bytes) -> int:
    sec, nsec = struct.unpack_from("<iI", raw, 4)       # CDR little-endian: after the 4-byte encapsulation header
    return sec * 1_000_000_000 + nsec


def _restamp(raw: bytes, stamp: int) -> bytes:
    out = bytearray(raw)
    struct.pack_into("<iI", out, 4, stamp // 1_000_000_000, stamp % 1_000_000_000)
    return bytes(out)


def write(tmp: Path, rig, spec: rosbags_rig.Spec, *, recorder: str = "host", one_camera: tuple | None = None,
          log_is_stamp: bool = False, device_status: bool = False, seed: int = 0) -> tuple[Path, dict]:
    """A rosbags bag of ``spec`` re-timed as recorded. ``recorder``: "host" (its clock takes the forward host
    steps, those of the ZED clock) or "steady"; ``one_camera``: (camera, trigger, ms), a step of that Boson's
    stamps alone; ``log_is_stamp``: log times copied from the header stamps (a converted bag: no receive clock);
    ``device_status``: each Boson status also carries ``realtime_minus_monotonic_ns`` and ``clock_step_ns`` as
    the device's node publishes them (firmware/device/clockstep.py: the host clock's steps since start-up, here
    the ZED-clock steps), added by field name to the DiagnosticStatus values."""
    truth = rosbags_rig.write(tmp / "raw", spec, rosbags_rig.project_layout(rig))
    topics = rosbags_rig.project_layout(rig)
    rng = np.random.default_rng(seed)
    ts = get_typestore(Stores.ROS2_HUMBLE)
    step_cam = {topics[one_camera[0]], topics[f"{one_camera[0]}_status"]} if one_camera else set()
    msgs = []
    with Reader(tmp / "raw") as r:
        for c, t, raw in r.messages():
            true = t - rosbags_rig.TRANSPORT_NS
            if c.topic in step_cam:
                cam, at, ms = one_camera
                if true >= rosbags_rig.T0_NS + at * P - 2e6:
                    old = _stamp(raw)
                    raw = _restamp(raw, old + int(ms * 1e6))
                    if c.topic == topics[cam]:
                        truth["trigger_of"][cam][old + int(ms * 1e6)] = truth["trigger_of"][cam].pop(old)
            if device_status and c.msgtype == "diagnostic_msgs/msg/DiagnosticArray":
                host = sum(int(ms * 1e6) for at, ms, on in spec.steps if on in ("zed", "all")
                           and true >= rosbags_rig.T0_NS + at * P - 2e6)
                m = ts.deserialize_cdr(raw, c.msgtype)
                kv = ts.types["diagnostic_msgs/msg/KeyValue"]
                for st in m.status:
                    st.values = list(st.values) + [kv(key="realtime_minus_monotonic_ns", value=str(REALTIME_MINUS_MONO
                                                                                                    + host)),
                                                   kv(key="clock_step_ns", value=str(host))]
                raw = bytes(ts.serialize_cdr(m, c.msgtype))
            clock = sum(int(ms * 1e6) for at, ms, on in spec.steps
                        if recorder == "host" and on in ("zed", "all") and ms > 0
                        and true >= rosbags_rig.T0_NS + at * P - 2e6)
            jitter = rng.gamma(2.0, 1.5e6) if "thermal" in c.topic else abs(rng.normal(0, 2e6))
            log = _stamp(raw) if log_is_stamp and c.msgtype.endswith("Image") else t + clock + int(jitter)
            msgs.append((log, c, raw))
    msgs.sort(key=lambda m: m[0])
    with Writer(tmp / "bag", version=8, storage_plugin=StoragePlugin.MCAP) as w:
        conns = {}
        for log, c, raw in msgs:
            if c.topic not in conns:
                conns[c.topic] = w.add_connection(c.topic, c.msgtype, typestore=ts)
            w.write(conns[c.topic], log, raw)
    if one_camera:
        truth["steps"] = list(truth["steps"]) + [one_camera]
    return tmp / "bag", truth


# ----------------------------------------------------------------------------- the pure parts
def test_candidates_are_one_per_frame_lost_at_the_step():
    """A +20 ms step in an interval of P + 20 ms: the stamps count 2 triggers and size it -13.3 ms; with no frame
    lost it is +20 ms, with one -13.3 ms, two -46.7 ms."""
    st = trigger.Step(10, 0, int(20e6 - P), exact=False)
    c = clocksteps.candidates(st, 2, P)
    assert c[:3] == pytest.approx([20e6, 20e6 - P, 20e6 - 2 * P], abs=1)
    assert len(c) == clocksteps.MAX_LOST + 1


def test_log_times_measure_the_step_whichever_clock_the_recorder_follows():
    """Stream A steps +50 ms at frame 40, B does not. The recorder steady: A's log - stamp drops by 50 ms; the
    recorder stepping with A: B's rises by 50 ms. Either way A - B is +50 ms."""
    rng = np.random.default_rng(1)
    n = 80
    true_a = 1e18 + np.arange(n) * P
    true_b = true_a + 7e6
    for recorder_step in (0.0, 50e6):
        ta = (true_a + np.where(np.arange(n) >= 40, 50e6, 0)).astype(np.int64)
        tb = true_b.astype(np.int64)
        rec = lambda t: (t + 4e6 + rng.normal(0, 1e6, n) + np.where(t >= true_a[40] - 1e6, recorder_step, 0))
        la, lb = rec(true_a).astype(np.int64), rec(true_b).astype(np.int64)
        m = clocksteps.log_time_step(ta, la, 40, tb, lb, P, "b")
        assert isinstance(m, clocksteps.Measured)
        assert m.step_ns == pytest.approx(50e6, abs=1.5e6) and m.stderr_ns < 1.5e6
        assert clocksteps.pick([50e6, 50e6 - P, 50e6 - 2 * P], m.step_ns, m.stderr_ns) == 50e6
    same = clocksteps.log_time_step(ta, ta, 40, tb, tb, P, "b")
    assert isinstance(same, str) and "header stamps" in same


def test_the_zed_right_follows_the_left_by_stamp_and_else_by_log_time():
    """The ZED left steps -100 ms at frame 5; the right has the same grabs but one the left lost (frame 7) and one
    restamped (frame 2): each is corrected as the left frame of its stamp, or the one logged nearest. -100 ms is
    three periods: frame 7's stamp is frame 4's, a grab logged 100 ms earlier, which must not decide."""
    t = (1e18 + np.arange(10) * P).astype(np.int64)
    left = np.where(np.arange(10) >= 5, t - int(100e6), t)
    st = trigger.Step(5, int(left[5]), int(-100e6), exact=True)
    keep = np.arange(10) != 7
    lc = clocksteps.corrected(left[keep], [trigger.Step(5, int(left[5]), st.step_ns, True)])
    assert (lc == t[keep]).all()
    right = left.copy()
    right[2] += 1000
    log = t + 5_000_000
    got = clocksteps.follow(right, log + 200_000, left[keep], log[keep], lc, P)
    assert (got == t + np.where(np.arange(10) == 2, 1000, 0)).all()


def test_a_measurement_between_two_candidates_picks_none():
    assert clocksteps.pick([20e6, 20e6 - P], 20e6 - P / 2, 1e6) is None


# ----------------------------------------------------------------------------- bags
#: a step on the ZED clock alone (what a host-clock step does to usb_cam's stamps: the Bosons keep their start-up
#: shift), no IMU; the recorder follows the forward steps (a backward one would reorder its log times: see
#: docs/dataset.md), and a step on one Boson's clock alone
CASES = {
    "zed +5 ms": ((100, 5.0, "zed"), None),
    "zed +20 ms": ((100, 20.0, "zed"), None),
    "zed +100 ms (3 periods: invisible in the stamps)": ((100, 100.0, "zed"), None),
    "zed +250 ms": ((100, 250.0, "zed"), None),
    "zed -5 ms": ((100, -5.0, "zed"), None),
    "zed -100 ms": ((100, -100.0, "zed"), None),
    "thermal_left alone +20 ms": (None, ("thermal_left", 100, 20.0)),
    "thermal_right alone -100 ms": (None, ("thermal_right", 90, -100.0)),
}


@pytest.mark.slow
@pytest.mark.parametrize("case", list(CASES), ids=str)
def test_a_step_on_one_clock_is_sized_and_every_pair_is_right(tmp_path, capsys, rig, case):
    step, one = CASES[case]
    spec = rosbags_rig.Spec(steps=(step,) if step else (), imu=False, seed=40 + len(case))
    bag, truth = write(tmp_path, rig, spec, one_camera=one, seed=len(case))
    code, out, err = run(capsys, "sync-check", str(bag), "--json", *LIMITS)
    assert code == 0, (err, out[-3000:])
    rep = json.loads(out)
    clock, ms = ("zed_left", step[1]) if step else (one[0], one[2])
    (ev,) = rep["clock_steps"]
    assert list(ev["clocks"]) == [clock]                      # which clock: that one alone
    c = ev["clocks"][clock]
    assert c["exact"] and c["sized_by"] == "log times" and c["step_ms"] == pytest.approx(ms, abs=1.0)
    assert "log - stamp against" in c["evidence"] and len(c["candidates_ms"]) == clocksteps.MAX_LOST + 1
    assert ev["step_ns"] / 1e6 == pytest.approx(ms, abs=1.0)
    for cam in ("thermal_left", "thermal_right"):            # the offset before the step: the written latency
        assert rep["triggers"][cam]["segments"][0]["offset_ms"] == pytest.approx(truth["latency_ms"][cam], abs=0.5)
    code, out, err = run(capsys, "sync-check", str(bag), *LIMITS)
    (line,) = [x for x in out.splitlines() if x.startswith(f"  {clock}: ")]     # the text names it too
    assert "sized by the log times" in line and "candidates" in line

    ds = tmp_path / "ds"
    code, out, err = run(capsys, "export", str(bag), "--out", str(ds), "--rate", "30", "--json", *LIMITS)
    assert code == 0, err
    rows = list(csv.DictReader((ds / "index.csv").open()))
    assert len(check_pairs(rows, truth, rig.desc.processing.ffc_margin_frames)) > 90
    (st,) = json.loads((ds / "export.json").read_text())["recordings"][0]["clock_steps"]
    assert list(st["clocks"]) == [clock]


@pytest.mark.slow
def test_without_a_receive_clock_the_step_is_refused_naming_what_is_missing(tmp_path, capsys, rig):
    """The same +20 ms ZED step in a bag whose image log times are the header stamps (as a converter writes them):
    nothing sizes it, and the trigger gaps after it are too few: sync-check fails (exit 1) and export refuses
    (exit 2), each in one line naming the file, the topic, the step with its candidates and the evidence missing;
    nothing written."""
    spec = rosbags_rig.Spec(steps=((100, 20.0, "zed"),), imu=False, seed=61)
    bag, _ = write(tmp_path, rig, spec, log_is_stamp=True)
    code, out, err = run(capsys, "sync-check", str(bag), "--json", *LIMITS)
    rep = json.loads(out)
    assert code == 1 and rep["verdict"] == "fail"
    (ev,) = rep["clock_steps"]
    z = ev["clocks"]["zed_left"]
    assert not z["exact"] and "header stamps" in z["evidence"]
    assert z["candidates_ms"][0] == pytest.approx(20.0, abs=1.0)        # no frame lost at it: the true size
    ds = tmp_path / "ds"
    code, out, err = run(capsys, "export", str(bag), "--out", str(ds), *LIMITS)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1, err
    for text in (str(bag), rig.desc.on_device.topics.thermal_left, "ambiguous", "missing evidence",
                 "the ZED clock stepped", "modulo one period", "candidates +", "header stamps", "IMU"):
        assert text in lines[0], (text, lines[0])
    assert not ds.exists()


@pytest.mark.slow
@pytest.mark.parametrize("ms,log_is_stamp", [(20.0, True), (-100.0, False)])
def test_the_device_status_sizes_a_host_step(tmp_path, capsys, rig, ms, log_is_stamp):
    """A host-clock step (the ZED's stamps follow it, usb_cam's do not) whose Boson status messages carry the
    device's clock_step_ns: in a bag with no receive clock the status alone sizes it; with one (a steady recorder:
    log times copied from the stamps would reorder the frames across a backward step, docs/dataset.md), the status
    and the log times agree. Said in the report; every exported pair is right."""
    spec = rosbags_rig.Spec(steps=((100, ms, "zed"),), imu=False, seed=61)
    bag, truth = write(tmp_path, rig, spec, recorder="steady", log_is_stamp=log_is_stamp, device_status=True)
    rec = open_recording(bag, rig)          # the index's one pass read the values the status topics hold
    assert set(rec.clock_step_values) == {"thermal_left", "thermal_right"}
    assert sync.device_clock_steps(rec) == sync.device_clock_steps(replace(rec, clock_step_values=None))
    code, out, err = run(capsys, "sync-check", str(bag), "--json", *LIMITS)
    assert code == 0, (err, out[-3000:])
    (ev,) = json.loads(out)["clock_steps"]
    z = ev["clocks"]["zed_left"]
    assert list(ev["clocks"]) == ["zed_left"] and z["exact"]
    assert z["sized_by"] == ("device status" if log_is_stamp else "log times and device status")
    assert z["step_ms"] == pytest.approx(ms, abs=1.0)
    for cam in ("thermal_left", "thermal_right"):
        assert f"{cam}'s device status clock_step_ns: {ms:+.1f} +- 0.1 ms" in z["evidence"]
    assert ("header stamps" in z["evidence"]) is False
    ds = tmp_path / "ds"
    code, out, err = run(capsys, "export", str(bag), "--out", str(ds), "--rate", "30", *LIMITS)
    assert code == 0, err
    assert len(check_pairs(list(csv.DictReader((ds / "index.csv").open())), truth,
                           rig.desc.processing.ffc_margin_frames)) > 90


@pytest.mark.slow
def test_frames_reordered_by_log_times_that_went_back_are_refused(tmp_path, capsys, rig):
    """A -100 ms ZED step in a bag whose image log times are the header stamps: read in log-time order, the ZED
    frames of the 100 ms after the step interleave with those before it (with the IMU recorded, which sizes the
    step). Before, sync-check passed and the export paired 3 triggers off; now both refuse in one line naming the
    file, the topic and what is missing, and nothing is written."""
    spec = rosbags_rig.Spec(steps=((100, -100.0, "zed"),), seed=61)
    bag, _ = write(tmp_path, rig, spec, recorder="steady", log_is_stamp=True)
    code, out, err = run(capsys, "sync-check", str(bag), *LIMITS)
    (fail,) = [line for line in out.splitlines() if line.startswith("FAIL trigger of every thermal frame")]
    assert code == 1 and "frames out of order" in fail
    ds = tmp_path / "ds"
    code, out, err = run(capsys, "export", str(bag), "--out", str(ds), *LIMITS)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1, err
    for text in (str(bag), rig.desc.on_device.topics.zed_left, "frames out of order", "orders messages by log time",
                 "missing evidence: the arrival order"):
        assert text in lines[0], (text, lines[0])
    assert not ds.exists()


def test_one_backward_step_is_not_disorder_but_interleaved_frames_are():
    t = (1e18 + np.arange(60) * P).astype(np.int64)
    stepped = np.where(np.arange(60) >= 30, t - int(100e6), t)
    assert clocksteps.out_of_order(stepped, P) is None
    # sorted (as log times equal to these stamps would be): frame 30 (27 P after the step) lands beside frame 27
    assert clocksteps.out_of_order(np.sort(stepped), P) == 28
