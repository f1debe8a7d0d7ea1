"""`platform_tools record-service` as a real process: the button pressed through file GPIO from this
test, SIGTERM during a recording, and `platform_tools doctor` against emulated Bosons."""
from __future__ import annotations

import json
import shutil
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from firmware.device import mcapcheck


def wait_for(cond, timeout=20.0):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if cond():
            return True
        time.sleep(0.05)
    return False


def events(out: Path) -> list[dict]:
    f = out / "events.jsonl"
    return [json.loads(x) for x in f.read_text().splitlines()] if f.exists() else []


def press(pins: Path, hold_s: float = 0.4) -> None:
    (pins / "pin29").write_text("0\n")
    time.sleep(hold_s)
    (pins / "pin29").write_text("1\n")


@pytest.mark.slow
def test_sigterm_during_a_recording_stops_it_cleanly(data_drive, dev_dir, tmp_path, overrides):
    _, out = data_drive
    pins = tmp_path / "pins"
    sets = [a for o in overrides() for a in ("--set", o)]
    proc = subprocess.Popen([sys.executable, "-m", "platform_tools.cli.main", "record-service", "--gpio",
                             f"file:{pins}", "--recorder", "fake", "--no-boson", "--dev-dir", str(dev_dir), *sets],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert wait_for(lambda: any(e["event"] == "ready" for e in events(out))), proc.stderr
        press(pins)
        assert wait_for(lambda: (pins / "pin31").exists() and (pins / "pin31").read_text().strip() == "1")
        # the recorder has its SIGINT handler once it says it records (on a loaded machine its start-up
        # takes seconds: a fixed sleep sent SIGINT to a process still importing)
        assert wait_for(lambda: any("fake_recorder: recording" in f.read_text() for f in out.glob("*/recorder.log")),
                        timeout=60)
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(timeout=20) == 0
    finally:
        if proc.poll() is None:
            proc.kill()
    [meta_file] = list(out.glob("*/recording.json"))
    meta = json.loads(meta_file.read_text())
    assert meta["status"] == "stopped" and meta["stop"]["reason"] == "service stopped (SIGTERM)", (meta["stop"], meta["faults"])
    assert meta["stop"]["signals"] == ["SIGINT"]
    assert all(mcapcheck.check(meta_file.parent / f["file"]).ok for f in meta["files"])
    assert (pins / "pin31").read_text().strip() == "0"           # LED off when the service is gone
    assert [e["event"] for e in events(out)][-1] == "exit"


@pytest.mark.slow
def test_bad_gpio_backend_is_one_line_exit_2(platform_tools):
    r = platform_tools("record-service", "--gpio", "banana")
    assert r.returncode == 2 and "--gpio banana" in r.stderr and "Traceback" not in r.stderr


# ----------------------------------------------------------------------------- doctor
@pytest.fixture
def bosons(tmp_path, monkeypatch):
    from platform_tools.boson import discovery
    from platform_tools.boson.emulator import BosonState, EmulatedBoson, Trigger
    from platform_tools.boson.emulator.state import FACTORY
    by_id = tmp_path / "by-id"
    by_id.mkdir()
    monkeypatch.setenv(discovery.BY_ID_ENV, str(by_id))
    monkeypatch.setenv(discovery.V4L_ENV, str(tmp_path / "v4l"))
    trigger = Trigger(30.0, running=True)
    emus = {}
    for side, sn in (("left", 93588), ("right", 93589)):
        # as boson-config leaves them: slave mode, telemetry rows on
        state = BosonState(sn, trigger=trigger, settings=dict(FACTORY, ext_sync_mode=2, telemetry_state=1, telemetry_location=1))
        emus[side] = EmulatedBoson(state, by_id_dir=by_id, boot_s=0.05, seed=sn).start()
    yield emus, trigger
    for e in emus.values():
        e.stop()


def doctor(overrides, dev_dir, *extra):
    sets = [a for o in overrides("sensors.thermal.left.serial=93588",
                                 "sensors.thermal.right.serial=93589") for a in ("--set", o)]
    r = subprocess.run([sys.executable, "-m", "platform_tools.cli.main", "doctor", "--json", "--dev-dir",
                        str(dev_dir), *sets, *extra], capture_output=True, text=True, timeout=60, env=os.environ)
    return r, {c["name"]: c for c in json.loads(r.stdout)["checks"]}


@pytest.mark.slow
def test_doctor_passes_with_cameras_triggered_in_slave_mode(overrides, dev_dir, bosons):
    r, checks = doctor(overrides, dev_dir, "--root", str(dev_dir.parent))     # no pinmux table there
    assert r.returncode == 0, r.stdout + r.stderr
    host = {"gpio pinmux", "host clock"}   # the host's: not measurable on this machine (tests/device/test_bringup.py)
    assert {n: c["status"] for n, c in checks.items() if n not in host} == dict.fromkeys(set(checks) - host, "ok")
    if shutil.which("chronyc") is None:
        assert checks["host clock"]["status"] == "skipped"
    assert checks["gpio pinmux"]["status"] == "skipped" and "not measurable here" in checks["gpio pinmux"]["detail"]
    assert json.loads(r.stdout)["cameras"]["left"]["serial"] == 93588


@pytest.mark.slow
def test_doctor_sees_the_trigger_stopped(overrides, dev_dir, bosons):
    _, trigger = bosons
    trigger.stop()
    r, checks = doctor(overrides, dev_dir)
    assert r.returncode == 1
    assert checks["trigger"]["status"] == "failed" and "0.0 Hz" in checks["trigger"]["detail"]


@pytest.mark.slow
def test_doctor_sees_a_wrong_sync_mode(overrides, dev_dir, bosons):
    emus, _ = bosons
    emus["right"].state.settings["ext_sync_mode"] = 0
    r, checks = doctor(overrides, dev_dir)
    assert r.returncode == 1
    assert checks["sync mode"]["status"] == "failed" and "right" in checks["sync mode"]["detail"]


@pytest.mark.slow
def test_doctor_sees_telemetry_off(overrides, dev_dir, bosons):
    emus, _ = bosons
    emus["left"].state.settings["telemetry_state"] = 0
    r, checks = doctor(overrides, dev_dir)
    assert r.returncode == 1
    assert checks["telemetry"]["status"] == "failed" and "left" in checks["telemetry"]["detail"]
    assert "FFC status" in checks["telemetry"]["detail"]


@pytest.mark.slow
def test_doctor_sees_a_missing_camera(overrides, dev_dir, bosons):
    emus, _ = bosons
    emus["left"].stop()
    r, checks = doctor(overrides, dev_dir)
    assert r.returncode == 1
    assert checks["thermal cameras"]["status"] == "failed" and "93588" in checks["thermal cameras"]["detail"]


@pytest.mark.slow
def test_doctor_fails_when_output_is_not_on_the_data_drive(dev_dir, tmp_path, platform_tools):
    r = platform_tools("doctor", "--json", "--no-boson", "--dev-dir", str(dev_dir), "--set",
                       f"recording.data_mount={tmp_path}", "--set", f"recording.output_dir={tmp_path}/rec")
    checks = {c["name"]: c for c in json.loads(r.stdout)["checks"]}
    assert r.returncode == 1
    assert checks["data drive"]["status"] == "failed" and "not a mount point" in checks["data drive"]["detail"]
