"""`rig-device boson-config`, the device's Boson set-up (firmware/commands/boson_config.py over
platform_tools.boson.rigconfig), run for real against emulated Bosons on ptys: what it does to the cameras,
that it is the workstation's `platform_tools boson-config` (same JSON on the same set-up), that it finds the
cameras by the only names a device container has (the rig's udev names), and that it runs from the device
images' build context alone."""
from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from firmware.cli import main as rig_device
from firmware.render import write
from platform_tools.boson import commands as C
from platform_tools.boson import discovery
from platform_tools.boson.emulator.state import FACTORY
from platform_tools.cli.main import main as platform_tools
from platform_tools.rig import load_rig
from tests.boson.conftest import LEFT, RIG_SERIALS, RIGHT, by_id, make_boson, trigger  # noqa: F401  fixtures

SLAVE = int(C.ExtSyncMode.SLAVE)
# a reply is waited for 2 s (the pty answers in milliseconds): no timeout, hence no retry, on a loaded machine
LINK = ["--timeout", "2", "--retries", "2", "--reopen-timeout", "3"]


def run(tool, capsys, *argv: str):
    code = tool([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def configured_as_the_rig_wants(emu) -> bool:
    s = emu.state.settings
    return (s["ext_sync_mode"] == SLAVE and s["telemetry_state"] == C.TelemetryState.ENABLED
            and s["telemetry_location"] == C.TelemetryLocation.BOTTOM)


@pytest.mark.slow
def test_slave_configures_both_and_its_json_is_the_workstation_commands(make_boson, capsys):
    pair = make_boson(LEFT), make_boson(RIGHT)
    code, out, err = run(rig_device, capsys, "boson-config", "--slave", "--json", *RIG_SERIALS, *LINK)
    assert code == 0, err
    device = json.loads(out)
    assert all(configured_as_the_rig_wants(emu) for emu in pair)
    assert [(c["label"], c["serial"], c["status"]) for c in device["cameras"]] == \
        [("left", LEFT, "configured"), ("right", RIGHT, "configured")]
    assert all(emu.state.flash_writes == 0 for emu in pair)          # not persisted: flash untouched
    for emu in pair:                               # the same set-up again: two cameras at factory settings
        emu.stop()
    fresh = make_boson(LEFT), make_boson(RIGHT)
    assert all(emu.state.settings == FACTORY for emu in fresh) and fresh[0].port == pair[0].port
    code, out, err = run(platform_tools, capsys, "boson-config", "--slave", "--json", *RIG_SERIALS, *LINK)
    assert code == 0, err
    assert json.loads(out) == device


def test_a_missing_camera_is_exit_2_naming_it_and_the_other_is_untouched(make_boson, capsys):
    left = make_boson(LEFT)
    code, out, err = run(rig_device, capsys, "boson-config", "--slave", "--json", *RIG_SERIALS, *LINK)
    assert code == 2 and out == ""
    (line,) = err.strip().splitlines()
    assert line.startswith("rig-device: error: ") and f"right camera (SN {RIGHT}) not found" in line
    assert f"SN {LEFT}" in line                                     # what was found instead
    # read back from the emulator: RAM and flash as they were, asked its serial number and nothing else
    assert left.state.settings == FACTORY and left.state.flash == FACTORY
    assert left.state.flash_writes == 0 and left.requests == 1


@pytest.mark.slow
def test_cameras_are_found_by_the_rig_udev_names_a_container_has(make_boson, tmp_path, monkeypatch, capsys):
    """The recorder container is given /dev/<device_name>_serial only (no /dev/serial/by-id)."""
    pair = make_boson(LEFT), make_boson(RIGHT)
    dev = tmp_path / "dev"
    dev.mkdir()
    rig = load_rig(None, [RIG_SERIALS[1], RIG_SERIALS[3]])
    for side, emu in zip(("left", "right"), pair):
        os.symlink(emu.path, dev / rig.boson_device_nodes(side)["serial"])
    empty = tmp_path / "no-by-id"
    empty.mkdir()
    monkeypatch.setenv(discovery.BY_ID_ENV, str(empty))
    # without them (--dev-dir elsewhere) such a container finds no camera: bad input, nothing written
    code, _, err = run(rig_device, capsys, "boson-config", "--slave", "--dev-dir", empty, *RIG_SERIALS, *LINK)
    assert code == 2 and f"left camera (SN {LEFT}) not found" in err and "no Boson found" in err
    assert all(emu.state.settings == FACTORY for emu in pair)
    code, out, err = run(rig_device, capsys, "boson-config", "--slave", "--json", "--dev-dir", dev, *RIG_SERIALS,
                         *LINK)
    assert code == 0, err
    doc = json.loads(out)
    assert [c["port"] for c in doc["cameras"]] == [str(dev / rig.boson_device_nodes(s)["serial"])
                                                   for s in ("left", "right")]
    assert all(configured_as_the_rig_wants(emu) for emu in pair)


@pytest.mark.slow
def test_it_runs_from_the_device_build_context_alone(make_boson, tmp_path):
    """A fresh process whose only copy of this repository is the rendered build context the device images
    install (firmware, platform_tools.rig, platform_tools.boson): the module imports, every project module
    comes from there, --help states the exit codes, and the command configures both cameras."""
    pair = make_boson(LEFT), make_boson(RIGHT)
    write(load_rig(None, [RIG_SERIALS[1], RIG_SERIALS[3]]), tmp_path / "fw")
    src = tmp_path / "fw" / "docker" / "src" / "rgbt-rig"
    rig_file = tmp_path / "fw" / "config" / "rig.yaml"      # the rig the compose stack gives rig-device
    assert not (src / "platform_tools" / "cli").exists()
    probe = ("import contextlib, io, json, sys\n"
             "import firmware.commands.boson_config\n"
             "from firmware.cli import main\n"
             "help = io.StringIO()\n"
             "with contextlib.redirect_stdout(help), contextlib.suppress(SystemExit):\n"
             "    main(['boson-config', '--help'])\n"
             f"code = main(['boson-config', '--slave', '--json', '--rig', {str(rig_file)!r}, "
             f"*{RIG_SERIALS + LINK!r}])\n"
             "ours = [m for m in sys.modules if m.split('.')[0] in ('firmware', 'platform_tools', 'calibration', "
             "'cad', 'bom', 'tests')]\n"
             f"outside = [m for m in ours if not (sys.modules[m].__file__ or '').startswith({str(src)!r})]\n"
             "print(json.dumps({'help': help.getvalue(), 'code': code, 'outside': outside}))\n")
    r = subprocess.run([sys.executable, "-c", probe], cwd=tmp_path, env=dict(os.environ, PYTHONPATH=str(src)),
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    last = json.loads(r.stdout.strip().splitlines()[-1])
    assert last["outside"] == [] and last["code"] == 0, r.stderr
    assert "Exit codes: 0 every camera" in last["help"] and "1 a camera failed" in last["help"] \
        and "2 bad input" in last["help"]
    assert all(opt in last["help"] for opt in ("--slave", "--no-sync", "--persist", "--check-trigger", "--json",
                                               "--timeout", "--dev-dir"))
    assert all(configured_as_the_rig_wants(emu) for emu in pair)
