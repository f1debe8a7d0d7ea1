"""Fixtures: emulated Bosons on real pseudo-terminals, published in a per-test by-id folder that
discovery is pointed at, and the real CLI run through main(argv)."""
from __future__ import annotations

import pytest

from platform_tools.boson import discovery
from platform_tools.boson.emulator import BosonState, EmulatedBoson, Trigger, parse_faults
from platform_tools.cli.main import main

LEFT, RIGHT = 93588, 93589
RIG_SERIALS = ["--set", f"sensors.thermal.left.serial={LEFT}", "--set", f"sensors.thermal.right.serial={RIGHT}"]
FAST = ["--timeout", "0.15", "--retries", "2", "--reopen-timeout", "3"]


@pytest.fixture
def by_id(tmp_path, monkeypatch):
    folder = tmp_path / "by-id"
    folder.mkdir()
    monkeypatch.setenv(discovery.BY_ID_ENV, str(folder))
    monkeypatch.setenv(discovery.V4L_ENV, str(tmp_path / "v4l-by-id"))
    return folder


@pytest.fixture
def trigger():
    return Trigger(30.0)


@pytest.fixture
def make_boson(by_id, trigger):
    """make_boson(serial, faults="busy:times=1", **state_kwargs) -> a started EmulatedBoson."""
    started: list[EmulatedBoson] = []

    def make(serial: int = LEFT, faults: str = "", boot_s: float = 0.2, **state_kw) -> EmulatedBoson:
        emu = EmulatedBoson(BosonState(serial, trigger=trigger, **state_kw), by_id_dir=by_id,
                            faults=parse_faults(faults), boot_s=boot_s, seed=serial)
        started.append(emu.start())
        return emu

    yield make
    for emu in started:
        emu.stop()


@pytest.fixture
def pair(make_boson):
    return make_boson(LEFT), make_boson(RIGHT)


@pytest.fixture
def cli(capsys):
    """cli(*argv) -> (exit code, stdout, stderr) of the real platform_tools CLI."""
    def run(*argv: str):
        code = main([str(a) for a in argv])
        out, err = capsys.readouterr()
        return code, out, err
    return run
