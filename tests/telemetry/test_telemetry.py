"""Boson telemetry on bytes: the layout at its documented offsets, encoder/decoder round trips, bad
input refused with one line, and the status publisher's pure part."""
from __future__ import annotations

import ast
import struct
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from platform_tools.boson.commands import FfcStatus
from platform_tools.boson import telemetry as D
from firmware.device.ffc_status import ERROR, OK, WARN, StatusTracker

LINE = 1280   # one 640-pixel Y16 row
U32 = st.integers(0, 2**32 - 1)
STATES = st.sampled_from(list(FfcStatus))


def test_fields_sit_at_the_documented_offsets_big_endian():
    """The offsets of the reference (Elphel Boson640Telemetry.java): status word 76 (8 bytes),
    frame counter 84, frame count at last FFC 88; big-endian."""
    line = D.encode_line(0x01020304, FfcStatus.IN_PROGRESS, 0x0A0B0C0D, LINE)
    assert len(line) == LINE
    assert line[84:88] == bytes([1, 2, 3, 4]) and line[88:92] == bytes([0x0A, 0x0B, 0x0C, 0x0D])
    assert struct.unpack_from(">Q", line, 76)[0] == 2 << D.FFC_SHIFT
    assert line[:76] == bytes(76) and line[92:] == bytes(LINE - 92)


def test_a_hand_built_line_decodes():
    buf = bytearray(LINE)
    struct.pack_into(">QII", buf, 76, 0x30 | 0x100, 1000, 940)    # FFC complete, another status bit set
    t = D.decode_line(bytes(buf))
    assert (t.frame_counter, t.ffc_status, t.ffc_frame, t.frames_since_ffc) == (1000, FfcStatus.COMPLETE, 940, 60)
    assert t.status_word == 0x130 and not t.ffc_in_progress


@settings(max_examples=200, deadline=None)
@given(counter=U32, state=STATES, ffc=U32, other=st.integers(0, 2**64 - 1),
       nbytes=st.integers(D.MIN_LINE_BYTES, 4 * LINE))
def test_round_trip(counter, state, ffc, other, nbytes):
    t = D.decode_line(D.encode_line(counter, state, ffc, nbytes, status_word=other))
    assert (t.frame_counter, t.ffc_status, t.ffc_frame) == (counter, state, ffc)
    assert t.frames_since_ffc == (counter - ffc) % 2**32          # wraps with the 32-bit counter
    assert t.status_word & ~(D.FFC_MASK << D.FFC_SHIFT) == other & ~(D.FFC_MASK << D.FFC_SHIFT)


@settings(max_examples=60, deadline=None)
@given(counter=U32, state=STATES, ffc=U32, width=st.integers(24, 96), height=st.integers(1, 40),
       rows=st.integers(1, 3), location=st.sampled_from(D.LOCATIONS), seed=st.integers(0, 2**16))
def test_round_trip_through_a_frame_and_its_message_bytes(counter, state, ffc, width, height, rows, location, seed):
    """Written into the telemetry rows of a frame, read back from the array and from the raw bytes
    of a mono16 sensor_msgs/Image; the image rows are untouched."""
    if rows * width * 2 < D.MIN_LINE_BYTES:
        with pytest.raises(D.TelemetryError):
            D.write_into(np.zeros((height + rows, width), np.uint16), bytes(D.MIN_LINE_BYTES), rows, location)
        return
    image = np.random.default_rng(seed).integers(0, 65535, (height, width), dtype=np.uint16)
    blank = np.zeros((rows, width), np.uint16)
    frame = np.vstack([image, blank] if location == "bottom" else [blank, image])
    frame = D.write_into(frame, D.encode_line(counter, state, ffc, rows * width * 2), rows, location)
    got_image, _ = D.split_frame(frame, rows, location)
    assert np.array_equal(got_image, image)
    for t in (D.decode_frame(frame, rows, location),
              D.decode_image_data(frame.astype("<u2").tobytes(), height + rows, width * 2, rows, location)):
        assert (t.frame_counter, t.ffc_status, t.ffc_frame) == (counter, state, ffc)


@settings(max_examples=300, deadline=None)
@given(data=st.binary(max_size=400))
def test_any_bytes_decode_or_fail_with_one_line(data):
    """Arbitrary bytes never crash the decoder: a Telemetry with a valid FFC state, or TelemetryError."""
    try:
        t = D.decode_line(data)
    except D.TelemetryError as exc:
        assert len(data) < D.MIN_LINE_BYTES and "\n" not in str(exc)
        return
    assert t.ffc_status in set(FfcStatus) and 0 <= t.frame_counter < 2**32 and 0 <= t.frames_since_ffc < 2**32


@settings(max_examples=200, deadline=None)
@given(data=st.binary(max_size=600), height=st.integers(-2, 20), step=st.integers(-4, 200),
       rows=st.integers(-1, 4), location=st.sampled_from(D.LOCATIONS + ("middle",)))
def test_any_image_data_decodes_or_fails_with_one_line(data, height, step, rows, location):
    try:
        D.decode_image_data(data, height, step, rows, location)
    except D.TelemetryError as exc:
        assert "\n" not in str(exc)


def test_frames_without_room_are_refused():
    with pytest.raises(D.TelemetryError, match="no telemetry"):
        D.decode_frame(np.zeros((514, 640), np.uint16), 0)
    with pytest.raises(D.TelemetryError, match="cannot hold"):
        D.decode_frame(np.zeros((2, 640), np.uint16), 2)
    with pytest.raises(D.TelemetryError, match="at least 92"):
        D.encode_line(1, 0, 0, 64)


@pytest.mark.parametrize("w,h,present", [(640, 514, True), (640, 512, False), (96, 78, True), (96, 76, False),
                                         (64, 53, True), (64, 51, False), (640, 480, False)])
def test_telemetry_rows_recognised_from_the_frame_size(w, h, present):
    assert D.telemetry_rows_present(w, h, 640, 512, 2) is present
    assert D.telemetry_rows_present(w, h, 640, 512, 0) is False


# ----------------------------------------------------------------------------- the publisher's pure part
def frame_bytes(counter: int, state: FfcStatus, ffc: int, width=640, height=514) -> bytes:
    frame = D.write_into(np.zeros((height, width), np.uint16), D.encode_line(counter, state, ffc, 2 * width * 2), 2)
    return frame.astype("<u2").tobytes()


def values(msg: dict) -> dict:
    return {kv["key"]: kv["value"] for kv in msg["status"][0]["values"]}


def test_status_per_frame_with_the_frame_stamp():
    tr = StatusTracker("thermal_left", "93588", rows=2)
    seq = [(100, FfcStatus.NONE), (101, FfcStatus.IMMINENT), (102, FfcStatus.IN_PROGRESS),
           (104, FfcStatus.IN_PROGRESS), (105, FfcStatus.COMPLETE), (105, FfcStatus.COMPLETE)]
    out = [tr.on_frame(1_000_000_000 * (i + 1) + 5, frame_bytes(c, s, 50 if c < 102 else 102), 514, 1280)
           for i, (c, s) in enumerate(seq)]
    assert all(m is not None for m in out)
    assert [m["header"]["stamp"] for m in out[:2]] == [{"sec": 1, "nanosec": 5}, {"sec": 2, "nanosec": 5}]
    assert [values(m)["ffc_status"] for m in out] == ["0", "1", "2", "2", "3", "3"]
    assert [values(m)["ffc_in_progress"] for m in out] == ["0", "0", "1", "1", "0", "0"]
    assert values(out[0])["frames_since_ffc"] == "50" and values(out[4])["frames_since_ffc"] == "3"
    assert [values(m)["missed_frames"] for m in out] == ["0", "0", "0", "1", "0", "0"]   # 102 -> 104
    assert [m["status"][0]["level"] for m in out] == [OK, WARN, WARN, WARN, OK, ERROR]   # 105 twice: stale
    assert out[0]["status"][0]["hardware_id"] == "93588" and out[0]["status"][0]["name"] == "thermal_left"


def test_status_with_a_period_publishes_changes_and_then_once_per_period():
    tr = StatusTracker("thermal_right", "93599", rows=2, period_s=1.0)
    stamps = [int(k * 1e9 / 30) for k in range(90)]
    states = [FfcStatus.NONE] * 40 + [FfcStatus.IN_PROGRESS] * 15 + [FfcStatus.COMPLETE] * 35
    out = [tr.on_frame(t, frame_bytes(1000 + k, s, 900), 514, 1280) for k, (t, s) in enumerate(zip(stamps, states))]
    published = [k for k, m in enumerate(out) if m is not None]
    assert published == [0, 30, 40, 55, 85]      # start, 1 s, FFC starts, FFC ends, 1 s after that


def test_a_frame_without_telemetry_is_an_error_status():
    tr = StatusTracker("thermal_left", "1", rows=2)
    m = tr.on_frame(7, b"\0" * 100, 514, 1280)
    assert m["status"][0]["level"] == ERROR and values(m)["ffc_status"] == "-1"
    assert "no telemetry" in m["status"][0]["message"]


def test_the_node_module_is_only_glue():
    """ffc_node.py needs rclpy (device only); its logic lives in ffc_status.py. Check it parses and uses it."""
    import firmware.device.ffc_status as status
    src = (Path(status.__file__).parent / "ffc_node.py").read_text()
    tree = ast.parse(src)
    imported = {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)} | \
        {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
    assert {"rclpy.node", "sensor_msgs.msg", "diagnostic_msgs.msg", "firmware.device.ffc_status",
            "firmware.device.rosnode"} <= imported
    assert "StatusTracker" in src and "def main" in src


# ----------------------------------------------------------------------------- host clock steps (issue 18)
def test_a_host_clock_step_is_in_the_status_and_undoes_the_thermal_stamp_error():
    """A simulated host: monotonic time m, realtime = m + offset, the offset stepped by +2.5 s (chrony's
    makestep) at frame 50. usb_cam's stamp is m + the offset at its start; the truth is the realtime."""
    from firmware.device.clockstep import ClockSteps, corrected_stamp_ns
    offset0, step = 1_700_000_000_000_000_000, 2_500_000_000
    frame = {"k": 0}

    def offset_now() -> int:        # what CLOCK_REALTIME - CLOCK_MONOTONIC reads at the current frame
        return offset0 + (step if frame["k"] >= 50 else 0) + 3 * frame["k"]     # + a slew of 3 ns per frame

    clock = ClockSteps(offset_now)                 # the node starts with usb_cam: offset0
    tr = StatusTracker("thermal_left", "93588", rows=2, clock=clock)
    errors_before, errors_after = [], []
    for k in range(100):
        frame["k"] = k
        mono = 5_000_000_000 + k * 33_333_333
        usb_cam_stamp = mono + offset0             # its shift was computed once, at start
        truth = mono + offset_now()
        msg = tr.on_frame(usb_cam_stamp, frame_bytes(1000 + k, FfcStatus.NONE, 900), 514, 1280)
        v = values(msg)
        assert int(v["realtime_minus_monotonic_ns"]) == offset_now()
        errors_before.append(truth - usb_cam_stamp)
        errors_after.append(truth - corrected_stamp_ns(usb_cam_stamp, int(v["clock_step_ns"])))
    assert max(errors_before[50:]) >= step                 # the uncorrected stamps are 2.5 s off after the step
    assert errors_after == [0] * 100                       # the corrected ones are exact


def test_a_step_is_published_at_once_even_when_rate_limited():
    from firmware.device.clockstep import ClockSteps
    offsets = iter([0] + [0] * 10 + [-7_000_000] * 20)     # start, 10 frames, then the clock steps back 7 ms
    tr = StatusTracker("thermal_right", "93599", rows=2, period_s=10.0, clock=ClockSteps(lambda: next(offsets)))
    out = [tr.on_frame(int(k * 1e9 / 30), frame_bytes(1000 + k, FfcStatus.NONE, 900), 514, 1280) for k in range(30)]
    published = [k for k, m in enumerate(out) if m is not None]
    assert published == [0, 10] and values(out[10])["clock_step_ns"] == "-7000000"


def test_the_offset_is_read_between_two_monotonic_reads():
    import time
    from firmware.device.clockstep import realtime_minus_monotonic_ns
    reads = {time.CLOCK_MONOTONIC: iter([100, 140]), time.CLOCK_REALTIME: iter([1_000_120])}
    assert realtime_minus_monotonic_ns(lambda c: next(reads[c])) == 1_000_120 - 120
    real = realtime_minus_monotonic_ns()
    assert abs(real - (time.time_ns() - time.monotonic_ns())) < 50_000_000    # the same clocks, read again
