"""The recorder state machine with a real fake-recorder process, driven through the button loop
(MemoryGpio) or directly, and every fault of the issue: a missing camera, a crash, a hang on SIGINT,
the disk filling, power loss. The recording already written is never lost; the next press works."""
from __future__ import annotations

import json
import os
import signal
import time

import pytest

from firmware.device import led, mcapcheck, metadata
from firmware.device.button import Button, Press
from firmware.device.gpio import MemoryGpio
from firmware.device.recorder import ButtonLoop, Recorder, State
from firmware.device.storage import free_bytes


def wait_for(cond, timeout=15.0, step=0.02):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if cond():
            return True
        time.sleep(step)
    return False


#: bytes of MCAP on disk that prove the recorder is writing (more than one 64 KiB chunk of the fake recorder)
WRITTEN_BYTES = 128 * 1024


def wait_written(rec: Recorder, timeout: float = 60.0) -> None:
    """Wait until the running recording has chunks on disk: a recorder process starts slowly on a loaded
    machine, and a fixed sleep would then stop or kill it before it wrote anything."""
    def written() -> bool:
        files = list(rec.session.bag.glob("*.mcap")) if rec.session and rec.session.bag.exists() else []
        return sum(f.stat().st_size for f in files) >= WRITTEN_BYTES
    assert wait_for(written, timeout), "the recorder wrote no chunk"


def ticking_until_error(rec: Recorder, timeout: float) -> bool:
    """Run the periodic checks (the button loop does this every 10 ms) until the state is ERROR."""
    def cond():
        rec.tick()
        return rec.state is State.ERROR
    return wait_for(cond, timeout, 0.01)


def events(rec: Recorder) -> list[dict]:
    return [json.loads(ln) for ln in (rec.output_dir / "events.jsonl").read_text().splitlines()]


def record_for(rec: Recorder, seconds: float) -> dict:
    assert rec.start(), events(rec)[-1]
    wait_written(rec)
    time.sleep(seconds)
    rec.press(Press.SHORT)
    assert rec.wait_stopped(20)
    return rec.finished[-1]


@pytest.mark.slow
def test_press_records_press_stops_with_a_checked_file_and_metadata(make_recorder):
    rec = make_recorder()
    meta = record_for(rec, 1.0)
    assert rec.state is State.IDLE
    assert meta["status"] == "stopped" and meta["stop"]["signals"] == ["SIGINT"]
    assert meta["rig"]["hash"] == rec.rig.hash and meta["software"]
    assert set(meta["cameras"]) == {"left", "right"} and meta["started_utc"] < meta["stopped_utc"]
    [f] = meta["files"]
    assert f["indexed"] and f["readable"] and f["messages"] > 0 and "recovered" not in f
    on_disk = metadata.read(rec.output_dir / meta["name"])
    assert on_disk == json.loads(json.dumps(meta))
    assert (rec.output_dir / meta["name"] / "bag" / "metadata.yaml").is_file()


@pytest.mark.slow
def test_the_button_loop_with_a_bouncing_button_starts_one_recording(make_recorder):
    rec = make_recorder()
    gpio = MemoryGpio()
    loop = ButtonLoop(rec, gpio, Button(0.2, 3.0), pin=29, led_pin=31)

    def run(seconds, level=None, chatter=False):
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            if level is not None:
                gpio.levels[29] = (level if not chatter else int(time.monotonic() * 200) % 2)
            loop.step()
            time.sleep(0.005)

    run(0.1, chatter=True, level=0)     # 100 ms of contact chatter
    run(0.4, level=0)                   # then held
    run(0.4, level=1)                   # released
    assert rec.state is State.RECORDING
    assert gpio.levels[31] == 1         # LED on while recording
    wait_written(rec)                   # the recorder is up (its SIGINT handler installed) before the stop
    run(0.4, level=0)
    run(0.4, level=1)
    assert wait_for(lambda: rec.state is State.IDLE, timeout=60)
    assert len(rec.finished) == 1 and len([e for e in events(rec) if e["event"] == "recording started"]) == 1


@pytest.mark.slow
def test_missing_camera_refuses_to_start_then_the_next_press_works(make_recorder, dev_dir):
    rec = make_recorder()
    (dev_dir / "boson_right_video").unlink()
    assert not rec.start()
    assert rec.state is State.ERROR and rec.error_code is led.ErrorCode.PREFLIGHT
    assert not any(p.is_dir() for p in rec.output_dir.iterdir())          # nothing half-made
    fault = [e for e in events(rec) if e["event"] == "fault"][-1]
    assert "boson_right_video" in fault["message"] and fault["blinks"] == 1
    (dev_dir / "boson_right_video").touch()
    assert record_for(rec, 0.5)["status"] == "stopped"


@pytest.mark.slow
def test_recorder_crash_mid_run_keeps_what_was_written(make_recorder):
    rec = make_recorder("die-after:1.5")
    assert rec.start()
    assert ticking_until_error(rec, 20)
    assert rec.error_code is led.ErrorCode.RECORDER_CRASHED
    meta = rec.finished[-1]
    [f] = meta["files"]
    assert not f["indexed"] and f["recovered"]["messages"] > 0
    recovered = rec.output_dir / meta["name"] / f["recovered"]["path"]
    assert mcapcheck.check(recovered).ok
    assert any("exited with status 3" in e.get("message", "") for e in events(rec))
    assert rec.start() and rec.state is State.RECORDING                   # the next press works


@pytest.mark.slow
def test_recorder_hanging_on_sigint_is_escalated_and_recovered(make_recorder):
    rec = make_recorder("hang-on-sigint", "recording.stop_grace_s=0.6", "on_device.recorder_term_grace_s=0.4")
    meta = record_for(rec, 1.0)
    assert meta["stop"]["signals"] == ["SIGINT", "SIGTERM", "SIGKILL"]
    assert meta["stop"]["seconds"] >= 1.0
    assert meta["files"][0]["recovered"]["messages"] > 0
    assert rec.state is State.ERROR and rec.error_code is led.ErrorCode.RECORDER_HUNG
    assert any(e.get("code") == "RECORDER_HUNG" for e in events(rec))


@pytest.mark.slow
def test_disk_watchdog_stops_cleanly_before_the_disk_fills(make_recorder, data_drive):
    """The watchdog threshold is put 60 MB below what is free now; the recorder writes ~40 MB/s."""
    mount, _ = data_drive
    margin = 60e6
    stop_at_gb = (free_bytes(mount) - margin) / 1e9
    rec = make_recorder("fill-disk", f"on_device.watchdog.stop_free_gb={stop_at_gb}")
    assert rec.start()
    assert ticking_until_error(rec, 30)
    assert rec.error_code is led.ErrorCode.DISK_FULL
    meta = rec.finished[-1]
    assert meta["stop"]["reason"] == "disk nearly full" and meta["stop"]["signals"] == ["SIGINT"]
    assert all(f["indexed"] and f["readable"] for f in meta["files"])
    # it stopped within about one check period of writing past the threshold
    assert free_bytes(mount) > stop_at_gb * 1e9 - 30e6


@pytest.mark.slow
def test_power_loss_leaves_a_truncated_file_that_the_next_start_recovers(make_recorder):
    rec = make_recorder()
    assert rec.start()
    wait_written(rec)
    session = rec.session
    os.killpg(session.proc.pid, signal.SIGKILL)          # the power goes: nothing closes
    session.proc.proc.wait()
    mcap = next(session.bag.glob("*.mcap"))
    os.truncate(mcap, mcap.stat().st_size - 100)         # and the last bytes never reached the disk
    rec.session = None
    assert metadata.read(session.folder)["status"] == "recording"

    after = make_recorder()                               # the service starts again after power-up
    after.output_dir = rec.output_dir
    assert after.recover_interrupted() == [session.name]
    meta = metadata.read(session.folder)
    assert meta["status"] == "interrupted" and meta["files"][0]["recovered"]["messages"] > 0
    assert mcap.exists()                                  # the original is kept as it was
    assert after.recover_interrupted() == []              # done once
    assert record_for(after, 0.5)["status"] == "stopped"  # and the next press works
