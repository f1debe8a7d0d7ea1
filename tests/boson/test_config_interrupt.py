"""Ctrl-C or SIGTERM in the middle of `boson-config --slave --persist`: a real process, over real ptys to two
emulated Bosons that each answer 0.25 s late, so that the set-up takes seconds and the signal lands inside a step.
The step in progress ends on every camera, then every camera is put back as after a failure, the report says so
and the exit code is 130; a signal during the last step (the flash write, then a reboot to verify it) lets it
end on both cameras. What the
cameras hold is read from the emulators (RAM, flash, flash writes), not taken from the tool's report."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from platform_tools.boson import commands as C
from platform_tools.boson.emulator.state import FACTORY
from tests.conftest import REPO

from .conftest import LEFT, RIG_SERIALS, RIGHT

pytestmark = [pytest.mark.slow, pytest.mark.skipif(not sys.platform.startswith("linux"), reason="ptys, signals")]

LATE = "delay:s=0.25"
#: a bound on waiting for the set-up to reach a state; reaching it later fails the test, sooner proves nothing
WAIT_S = 60


def _start(*extra: str, json_out: bool = True) -> subprocess.Popen:
    """The real command, in its own process group, with Ctrl-C at its default (as a terminal's foreground job has
    it; a background job started by a shell without job control ignores SIGINT)."""
    return subprocess.Popen([sys.executable, "-m", "platform_tools.cli.main", "boson-config", "--slave", "--persist",
                             *RIG_SERIALS, "--timeout", "1", "--retries", "2", *(["--json"] if json_out else []),
                             *extra],
                            cwd=REPO, env=os.environ.copy(), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))


def _wait(cond, p: subprocess.Popen, what: str) -> None:
    deadline = time.monotonic() + WAIT_S
    while not cond():
        if p.poll() is not None:
            pytest.fail(f"the command ended before {what}: {p.communicate()}")
        if time.monotonic() > deadline:
            p.kill()
            pytest.fail(f"gave up waiting for {what}")
        time.sleep(0.01)


def _slave(emu) -> bool:
    return emu.state.settings["ext_sync_mode"] == int(C.ExtSyncMode.SLAVE)


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["ctrl-c", "sigterm"])
def test_a_stop_after_the_switch_puts_every_camera_back(make_boson, sig):
    emus = [make_boson(LEFT, faults=LATE), make_boson(RIGHT, faults=LATE)]
    p = _start()
    _wait(lambda: any(_slave(e) for e in emus), p, "a camera to switch to slave")
    p.send_signal(sig)
    if sig == signal.SIGINT:
        time.sleep(0.1)
        p.send_signal(sig)                  # a second Ctrl-C does not cut the revert short
    out, err = p.communicate(timeout=WAIT_S)
    assert p.returncode == 130, err
    doc = json.loads(out)
    name = signal.Signals(sig).name
    assert doc["interrupted"] == name and not doc["ok"]
    assert [c["status"] for c in doc["cameras"]] == ["reverted", "reverted"], doc["cameras"]
    assert all(f"{name} came during the apply step" in c["error"] for c in doc["cameras"])
    for e in emus:                          # the truth: RAM and flash as they were, flash never written
        assert e.state.settings == FACTORY and e.state.flash == FACTORY and e.state.flash_writes == 0
    lines = [line for line in err.splitlines() if "writing SLAVE mode to flash" not in line]   # --persist's warning
    assert f"{name}: stopping after the apply step, then putting" in lines[0], err     # said once, at once
    assert len(lines) == 3 and all("error" in line and "reverted" in line for line in lines[1:]), err  # per camera


@pytest.mark.parametrize("json_out", [True, False], ids=["json", "table"])
def test_a_stop_while_the_cameras_are_read_writes_nothing(make_boson, json_out):
    emus = [make_boson(LEFT, faults=LATE), make_boson(RIGHT, faults=LATE)]
    p = _start("--no-read-flash", json_out=json_out)
    _wait(lambda: all(e.requests >= 2 for e in emus), p, "both cameras to be read")
    p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=WAIT_S)
    assert p.returncode == 130, err
    if json_out:
        doc = json.loads(out)
        assert [c["status"] for c in doc["cameras"]] == ["aborted", "aborted"], doc["cameras"]
    else:
        lines = out.splitlines()
        assert "persisted" not in lines[0] and lines[1] == "stopped by SIGINT: every camera was put back", out
        rows = [line.split() for line in lines if line.startswith("  ") and not line.startswith("    ")]
        assert [r[3] for r in rows] == ["aborted", "aborted"], out
    for e in emus:
        assert e.state.settings == FACTORY and e.state.flash_writes == 0


def test_a_stop_as_a_camera_fails_lets_its_revert_end_and_says_so(make_boson):
    # the right camera refuses its second write (the display mode), after the sync mode: the apply step fails
    refused = f"busy:fid=0x{C.SET_DISPLAY_MODE.function_id:08X}"
    emus = [make_boson(LEFT, faults=LATE), make_boson(RIGHT, faults=f"{LATE},{refused}")]
    p = _start("--display-mode", "one-shot")
    _wait(lambda: any(_slave(e) for e in emus), p, "a camera to switch to slave")
    p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=WAIT_S)
    assert p.returncode == 1, err           # the failure is the outcome; the signal changed nothing
    doc = json.loads(out)
    assert doc["interrupted"] is None and [c["status"] for c in doc["cameras"]] == ["reverted", "reverted"]
    assert "CamBusy" in doc["cameras"][1]["error"]
    assert all(any("SIGINT came as the set-up failed" in w for w in c["warnings"]) for c in doc["cameras"])
    for e in emus:
        assert e.state.settings == FACTORY and e.state.flash_writes == 0


def test_a_stop_during_the_flash_write_lets_it_end_on_both_cameras(make_boson):
    emus = [make_boson(LEFT, faults=LATE), make_boson(RIGHT, faults=LATE)]
    p = _start("--reboot-verify")       # the last step goes on after the write: a reboot, then a read-back
    _wait(lambda: any(e.state.flash_writes for e in emus), p, "a flash write")
    p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=WAIT_S)
    assert p.returncode == 0, err
    doc = json.loads(out)
    assert doc["interrupted"] is None and doc["ok"]
    assert [c["status"] for c in doc["cameras"]] == ["configured", "configured"]
    assert all(any("SIGINT came during the last step" in w for w in c["warnings"]) for c in doc["cameras"])
    assert "SIGINT: the last step (persist) is under way on every camera: letting it end" in err
    for e in emus:                          # both flashes new: not one new and one old
        assert _slave(e) and e.state.flash == e.state.settings and e.state.flash_writes == 1
