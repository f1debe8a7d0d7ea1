"""Fixtures: a data drive (a real mount other than /: /dev/shm), camera device nodes in a folder,
and a Recorder wired to the fake recorder process."""
from __future__ import annotations

import os
import shutil
import uuid
from pathlib import Path

import pytest

from firmware.device.bagproc import FakeBackend
from firmware.device.preflight import run_preflight
from firmware.device.recorder import Recorder
from platform_tools.rig import load_rig

SHM = Path("/dev/shm")
#: quick stops for tests: SIGINT grace 3 s, SIGTERM grace 1 s, the watchdog every 0.1 s
FAST = ("recording.stop_grace_s=3", "on_device.recorder_term_grace_s=1", "on_device.watchdog.check_period_s=0.1",
        "recording.min_free_gb=0.01", "on_device.watchdog.stop_free_gb=0.005")


@pytest.fixture
def data_drive():
    """(mount, output folder) on a real mount that is not the root filesystem."""
    if not os.path.ismount(SHM) or os.stat(SHM).st_dev == os.stat("/").st_dev:
        pytest.skip("/dev/shm is not a separate mount here")
    out = SHM / f"rgbt-test-{uuid.uuid4().hex[:8]}" / "recordings"
    yield SHM, out
    shutil.rmtree(out.parent, ignore_errors=True)


@pytest.fixture
def dev_dir(tmp_path) -> Path:
    d = tmp_path / "dev"
    d.mkdir()
    for name in ("boson_left_video", "boson_right_video"):
        (d / name).touch()
    return d


def rig_overrides(data_drive, *extra: str) -> list[str]:
    mount, out = data_drive
    return [f"recording.data_mount={mount}", f"recording.output_dir={out}", *FAST, *extra]


@pytest.fixture
def make_recorder(data_drive, dev_dir):
    made: list[Recorder] = []

    def make(misbehave: str = "none", *extra: str) -> Recorder:
        rig = load_rig(None, rig_overrides(data_drive, *extra))
        out = Path(rig.desc.recording.output_dir)
        # 19 recorded topics (camera_info, /tf_static, /diagnostics, /health/*: issue 18), each a mono16 image in the
        # fake recorder: 10 Hz keeps its SIGINT stop inside the short grace on a loaded machine
        rec = Recorder(rig, FakeBackend(misbehave, ("--rate-hz", "10")),
                       preflight=lambda: run_preflight(rig, out, boson=False, dev_dir=dev_dir))
        made.append(rec)
        return rec

    yield make
    for rec in made:
        if rec.session is not None and rec.session.proc is not None and rec.session.proc.poll() is None:
            rec.session.proc.stop(0.5, 0.5)


@pytest.fixture
def overrides(data_drive):
    """overrides(*extra) -> the --set values of a rig recording to the test's data drive."""
    return lambda *extra: rig_overrides(data_drive, *extra)
