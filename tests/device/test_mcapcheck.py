"""MCAP check and recovery on files the fake recorder wrote, cut at many points."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

from firmware.device import mcapcheck


@pytest.fixture(scope="module")
def clean_bag(tmp_path_factory):
    folder = tmp_path_factory.mktemp("bag") / "b"
    p = subprocess.Popen([sys.executable, "-m", "platform_tools.sim.fake_recorder", "-o", str(folder), "--misbehave", "fill-disk",
                          "--fill-mb-s", "4", "/a", "/b"],  # 1 MiB messages: many chunks
                         stderr=subprocess.DEVNULL)
    # until ten 1 MiB messages (and their frames) are on disk: the process starts slowly on a loaded machine
    end = time.monotonic() + 60
    while time.monotonic() < end and sum(f.stat().st_size for f in folder.glob("*.mcap")) < 10 * 2**20:
        time.sleep(0.05)
    p.send_signal(signal.SIGINT)
    assert p.wait(10) == 0
    return folder / "b_0.mcap"


@pytest.mark.slow
def test_a_cleanly_stopped_file_checks_ok(clean_bag):
    status = mcapcheck.check(clean_bag)
    assert status.ok and status.messages > 20


@pytest.mark.parametrize("keep", [0.3, 0.6, 0.9, 0.99])
def test_a_truncated_file_is_recovered_next_to_it(clean_bag, tmp_path, keep):
    cut = tmp_path / "cut.mcap"
    data = clean_bag.read_bytes()
    cut.write_bytes(data[:int(len(data) * keep)])
    assert not mcapcheck.check(cut).ok
    rec = mcapcheck.recover(cut)
    assert rec.path == str(tmp_path / "cut.recovered.mcap") and rec.stopped_at
    status = mcapcheck.check(tmp_path / "cut.recovered.mcap")
    assert status.ok and status.messages == rec.messages
    assert cut.read_bytes() == data[:int(len(data) * keep)]               # the original is untouched
    full = mcapcheck.check(clean_bag).messages
    assert 0 < rec.messages <= full          # a cut in the summary section loses no message
    if keep <= 0.6:
        assert rec.messages < full


def test_garbage_is_reported_not_raised(tmp_path):
    bad = tmp_path / "x.mcap"
    bad.write_bytes(os.urandom(5000))
    assert not mcapcheck.check(bad).ok
    assert mcapcheck.recover(bad).messages == 0
