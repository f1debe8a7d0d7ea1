"""The LED says when the power may be cut: on while recording and fast blinking while finishing (the
recorder closing its files, the post-stop check, recording.json, the flush to the drive), and only
then the idle blink. Driven through the button loop with the fake GPIO; the flush is held open to
watch the LED while the files are not yet on the drive."""
from __future__ import annotations

import os
import signal
import threading
import time

import pytest

from firmware.device import led, metadata, recorder as recorder_mod, storage
from firmware.device.button import Button
from firmware.device.gpio import MemoryGpio
from firmware.device.recorder import ButtonLoop, State

from tests.device.test_recorder import wait_for, wait_written

BUTTON, LED = 29, 31


def test_the_power_rule_of_every_led_state():
    assert [s for s in ("idle", "recording", "stopping", "error", "check_ok") if not led.power_may_be_cut(s)] == \
        ["recording", "stopping"]
    with pytest.raises(ValueError):
        led.power_may_be_cut("booting")


def test_sync_tree_flushes_every_file_and_folder(tmp_path, monkeypatch):
    (tmp_path / "bag").mkdir()
    for name in ("bag/bag_0.mcap", "bag/metadata.yaml", "recording.json"):
        (tmp_path / name).write_text("x")
    synced = []
    real = os.fsync
    monkeypatch.setattr(os, "fsync", lambda fd: (synced.append(os.readlink(f"/proc/self/fd/{fd}")), real(fd)))
    assert storage.sync_tree(tmp_path) == 5
    assert set(synced) == {str(tmp_path / p) for p in ("bag/bag_0.mcap", "bag/metadata.yaml", "recording.json",
                                                       "bag")} | {str(tmp_path)}


class HeldFlush:
    """sync_tree that waits for `release` and notes the recorder's state and the metadata at that moment."""

    def __init__(self, rec):
        self.rec, self.entered, self.release, self.seen = rec, threading.Event(), threading.Event(), []

    def __call__(self, folder):
        self.seen.append((self.rec.state, metadata.read(folder)["status"]))
        self.entered.set()
        assert self.release.wait(60)
        return storage.sync_tree(folder)


def _press(loop, gpio):
    for level, seconds in ((0, 0.4), (1, 0.4)):
        gpio.levels[BUTTON] = level
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            loop.step()
            time.sleep(0.005)


def _blinks_while(loop, gpio, cond, edges: int, timeout: float = 20.0) -> list[State]:
    """Step the loop until the LED rose `edges` times; returns the states seen meanwhile."""
    start, states = len(gpio.writes), []
    end = time.monotonic() + timeout
    while time.monotonic() < end and led.count_blinks([0] + [v for p, v in gpio.writes[start:] if p == LED]) < edges:
        loop.step()
        states.append(loop.recorder.state)
        time.sleep(0.005)
    assert led.count_blinks([0] + [v for p, v in gpio.writes[start:] if p == LED]) >= edges
    return states


@pytest.mark.slow
def test_the_led_says_do_not_cut_until_the_recording_is_on_the_drive(make_recorder, monkeypatch):
    rec = make_recorder()
    flush = HeldFlush(rec)
    monkeypatch.setattr(recorder_mod, "sync_tree", flush)
    gpio = MemoryGpio()
    loop = ButtonLoop(rec, gpio, Button(0.2, 3.0), pin=BUTTON, led_pin=LED)
    _press(loop, gpio)
    assert rec.state is State.RECORDING and gpio.levels[LED] == 1 and not led.power_may_be_cut(rec.state.value)
    wait_written(rec)
    _press(loop, gpio)                                     # stop
    assert flush.entered.wait(30)                          # closed, checked, recording.json written ...
    assert flush.seen == [(State.STOPPING, "stopped")]     # ... but not yet on the drive: still STOPPING
    states = _blinks_while(loop, gpio, None, edges=3)      # the LED blinks fast: do not cut
    assert set(states) == {State.STOPPING} and not led.power_may_be_cut("stopping")
    flush.release.set()
    assert wait_for(lambda: (loop.step(), rec.state is State.IDLE)[1])
    assert led.power_may_be_cut(rec.state.value)
    flushed = [e for e in (rec.output_dir / "events.jsonl").read_text().splitlines() if '"flushed"' in e]
    assert len(flushed) == 1


@pytest.mark.slow
def test_at_start_up_the_check_of_an_interrupted_recording_says_do_not_cut(make_recorder, monkeypatch):
    rec = make_recorder()
    assert rec.start()
    wait_written(rec)
    session = rec.session
    os.killpg(session.proc.pid, signal.SIGKILL)           # power loss mid-recording
    session.proc.proc.wait()
    rec.session = None

    after = make_recorder()                                # the service starts again after power-up
    after.output_dir = rec.output_dir
    flush = HeldFlush(after)
    monkeypatch.setattr(recorder_mod, "sync_tree", flush)
    gpio = MemoryGpio()
    loop = ButtonLoop(after, gpio, Button(0.2, 3.0), pin=BUTTON, led_pin=LED)
    after.recover_interrupted_async()
    assert flush.entered.wait(60)
    assert flush.seen == [(State.STOPPING, "interrupted")]
    states = _blinks_while(loop, gpio, None, edges=3)
    assert set(states) == {State.STOPPING}
    started = (after.output_dir / "events.jsonl").read_text().count('"recording started"')
    _press(loop, gpio)                                     # a press meanwhile is ignored
    assert after.state is State.STOPPING
    assert (after.output_dir / "events.jsonl").read_text().count('"recording started"') == started
    flush.release.set()
    assert after.wait_stopped(30) and after.state is State.IDLE and after.session is None
    assert metadata.read(session.folder)["status"] == "interrupted"
