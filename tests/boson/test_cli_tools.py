"""boson-info, boson-ffc, boson-restore-defaults, boson-raw and boson-emulator, run for real."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from platform_tools.boson import commands as C
from platform_tools.boson.emulator import parse_faults

from .conftest import FAST, LEFT, RIG_SERIALS, RIGHT

REPO = Path(__file__).resolve().parents[2]
PT = [sys.executable, "-m", "platform_tools.cli.main"]


def test_info_json_and_table(cli, pair, tmp_path):
    v4l = tmp_path / "v4l-by-id"
    v4l.mkdir()
    (v4l / f"usb-FLIR_Boson_{LEFT}-video-index0").symlink_to("/dev/null")
    pair[1].state.fpa_temp_c_x10 = -42
    code, out, _ = cli("boson-info", *RIG_SERIALS, *FAST, "--json")
    assert code == 0
    rows = {r["label"]: r for r in json.loads(out)["cameras"]}
    assert rows["left"]["serial"] == LEFT and rows["left"]["video"] == "/dev/null"
    assert rows["right"]["fpa_temp_c"] == -4.2 and rows["right"]["sync_mode"] == "disable"
    assert rows["left"]["firmware"] == "4.1.0" and rows["left"]["ffc_mode"] == "auto"
    code, out, _ = cli("boson-info", *FAST)
    assert code == 0 and str(LEFT) in out and str(RIGHT) in out and "sync_mode" in out


@pytest.mark.slow
def test_info_reports_a_dead_camera_and_the_live_one(cli, pair):
    pair[0].faults = parse_faults("stall")
    code, out, err = cli("boson-info", *RIG_SERIALS, *FAST, "--json")
    assert code == 1
    rows = {r["label"]: r for r in json.loads(out)["cameras"]}
    assert "error" in rows["left"] and rows["right"]["serial"] == RIGHT
    assert "left:" in err


def test_ffc_run_auto_manual(cli, pair):
    for emu in pair:
        emu.state.ffc_duration_s = 0.1
    code, out, _ = cli("boson-ffc", "run", *FAST, "--json")
    assert code == 0 and all(r["ffc_status"] == "complete" for r in json.loads(out)["cameras"])
    code, out, _ = cli("boson-ffc", "manual", "--camera", str(RIGHT), *FAST)
    assert code == 0 and pair[1].state.settings["ffc_mode"] == 0 and pair[0].state.settings["ffc_mode"] == 1


def test_restore_defaults(cli, pair):
    left, right = pair
    left.state.settings["ext_sync_mode"] = 2
    code, _, err = cli("boson-restore-defaults", *FAST)
    assert code == 2 and "--yes" in err and left.state.settings["ext_sync_mode"] == 2
    code, out, _ = cli("boson-restore-defaults", "--yes", "--persist", "--camera", str(LEFT), *FAST)
    assert code == 0 and left.state.settings["ext_sync_mode"] == 0 and left.state.flash_writes == 1
    assert right.state.flash_writes == 0


@pytest.mark.slow
def test_raw(cli, make_boson):
    emu = make_boson(LEFT)
    code, out, _ = cli("boson-raw", "0x00050002", *FAST)
    assert code == 0 and out.startswith("00016d94") and "93588" in out
    code, out, _ = cli("boson-raw", "0x00050098", "00000002", *FAST, "--json")
    assert code == 0 and json.loads(out)["status"] == "0x000" and emu.state.settings["ext_sync_mode"] == 2
    code, out, err = cli("boson-raw", "0x00050098", "00000009", *FAST, "--json")
    assert code == 1 and json.loads(out)["result"] == "RangeError" and "0x203" in err
    code, _, err = cli("boson-raw", "0x00050098", "0000", *FAST)
    assert code == 1 and "InsufficientBytes" in err


@pytest.mark.parametrize("argv", [("boson-raw", "zz"), ("boson-raw", "0x00050002", "0g"),
                                  ("boson-raw", "0x1FFFFFFFF")])
def test_raw_bad_input(cli, make_boson, argv):
    emu = make_boson(LEFT)
    code, out, err = cli(*argv, *FAST)
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1 and emu.requests == 0


def test_raw_needs_one_camera(cli, pair):
    code, _, err = cli("boson-raw", "0x00050002", *FAST)
    assert code == 2 and "one camera" in err


@pytest.mark.slow
@pytest.mark.parametrize("cmd", ["boson-config", "boson-info", "boson-ffc", "boson-restore-defaults",
                                 "boson-raw", "boson-emulator"])
def test_help(cmd):
    r = subprocess.run(PT + [cmd, "--help"], cwd=REPO, capture_output=True, text=True)
    assert r.returncode == 0 and "usage:" in r.stdout
    assert "Exit codes: 0" in r.stdout and " 2 bad input" in r.stdout


def _start_emulator(tmp_path, *extra):
    by_id = tmp_path / "emu-by-id"
    proc = subprocess.Popen(PT + ["boson-emulator", "--by-id-dir", str(by_id), *extra], cwd=REPO,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    lines = [proc.stdout.readline() for _ in range(2)]
    return proc, by_id, lines


@pytest.mark.slow
def test_emulator_process_serves_real_clients(tmp_path):
    proc, by_id, lines = _start_emulator(tmp_path, "--serial", str(LEFT), "--serial", str(RIGHT))
    try:
        sn, pty, link = lines[0].split()
        assert int(sn) == LEFT and pty.startswith("/dev/pts/") and os.readlink(link) == pty
        env = dict(os.environ, PLATFORM_TOOLS_BOSON_BY_ID=str(by_id))
        args = PT + ["boson-config", "--slave", "--check-trigger", "--check-seconds", "0.3", *RIG_SERIALS,
                     *FAST, "--json"]
        r = subprocess.run(args, cwd=REPO, env=env, capture_output=True, text=True)
        assert r.returncode == 1 and all(c["status"] == "reverted" for c in json.loads(r.stdout)["cameras"])
        proc.send_signal(signal.SIGUSR1)          # start the simulated trigger
        time.sleep(0.1)
        r = subprocess.run(args, cwd=REPO, env=env, capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        assert all(c["status"] == "configured" for c in json.loads(r.stdout)["cameras"])
    finally:
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=10)
    assert proc.returncode == 0 and not list(by_id.glob("usb-FLIR_Boson_*"))


@pytest.mark.slow
@pytest.mark.skipif(os.geteuid() != 0, reason="needs root to drop to an unprivileged user")
def test_permission_denied_on_the_port(tmp_path):
    proc, by_id, lines = _start_emulator(tmp_path, "--serial", str(LEFT))
    try:
        _, pty, _ = lines[0].split()
        os.chmod(pty, 0o600)
        env = dict(os.environ, PLATFORM_TOOLS_BOSON_BY_ID=str(by_id))
        r = subprocess.run(PT + ["boson-config", "--slave", "--port", pty, *FAST], cwd="/", env=env,
                           capture_output=True, text=True, user=65534, group=65534, extra_groups=[])
        if "No module named" in r.stderr or "can't open file" in r.stderr or "Errno 13" in r.stderr:
            pytest.skip(f"the unprivileged user cannot run the tool here: {r.stderr.strip()[-200:]}")
        assert r.returncode == 2 and "permission denied" in r.stderr and "dialout" in r.stderr
        assert len(r.stderr.strip().splitlines()) == 1 and r.stderr.count(pty) == 1
        assert "Traceback" not in r.stderr
    finally:
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=10)


@pytest.mark.slow
def test_emulator_session_writes_result_and_log(tmp_path):
    out = tmp_path / "session"
    r = subprocess.run(PT + ["boson-emulator", "--serial", str(LEFT), "--serial", str(RIGHT), "--trigger",
                             "--session-out", str(out), "--run", "boson-config", "--slave", "--check-trigger",
                             *RIG_SERIALS, "--json"], cwd=REPO, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    result = json.loads((out / "result.json").read_text())
    assert result["ok"] and {c["label"] for c in result["cameras"]} == {"left", "right"}
    log = [json.loads(l) for l in (out / "session.log").read_text().splitlines()]
    sets = [e for e in log if e.get("command") == "bosonSetExtSyncMode"]
    assert len(sets) == 2 and all(e["payload"] == "00000002" for e in sets)
    assert json.loads((out / "session.json").read_text())["exit_code"] == 0


def test_emulator_bad_faults(cli):
    code, _, err = cli("boson-emulator", "--faults", "explode")
    assert code == 2 and "unknown fault" in err


@pytest.mark.slow
@pytest.mark.parametrize("spec, says", [("93589", "expected SN=RULES"), ("777=delay", "SN 777 is not emulated"),
                                        ("93589=explode", "unknown fault")])
def test_emulator_bad_faults_on_one_camera(cli, spec, says):
    code, _, err = cli("boson-emulator", "--serial", str(LEFT), "--serial", str(RIGHT), "--faults-on", spec)
    assert code == 2 and f"--faults-on {spec!r}" in err and says in err


def test_faults_on_one_camera_reach_that_camera_only(tmp_path):
    from platform_tools.boson.emulator import Trigger
    from platform_tools.boson.emulator.fleet import Fleet
    with Fleet([LEFT, RIGHT], trigger=Trigger(30.0), by_id_dir=tmp_path, faults=parse_faults("split"),
               faults_for={RIGHT: parse_faults("delay:s=1.5")}) as fleet:
        kinds = {e.serial: [f.kind for f in e.faults] for e in fleet.cameras}
    assert kinds == {LEFT: ["split"], RIGHT: ["split", "delay"]}


@pytest.mark.parametrize("fid", sorted(C.FLASH_OR_REBOOT))
def test_raw_refuses_flash_and_reboot_without_yes(cli, make_boson, fid):
    emu = make_boson(LEFT)
    code, out, err = cli("boson-raw", f"0x{fid:08X}", *FAST)
    assert code == 2 and out == "" and "--yes" in err and C.BY_ID[fid].name in err
    assert emu.requests == 0 and emu.state.flash_writes == 0 and emu.state.boots == 1


def test_raw_sends_a_flash_write_with_yes(cli, make_boson):
    emu = make_boson(LEFT)
    code, out, err = cli("boson-raw", f"0x{C.WRITE_FLASH.function_id:08X}", "--yes", *FAST, "--json")
    assert code == 0, err
    assert emu.state.flash_writes == 1 and json.loads(out)["status"] == "0x000"


def test_raw_camera_error_names_the_camera_once(cli, make_boson):
    make_boson(LEFT)
    code, _, err = cli("boson-raw", "0x00050098", "00000009", "--camera", str(LEFT), *FAST)
    assert code == 1 and err.count(f"SN {LEFT}") == 1 and "RangeError" in err


def test_a_port_that_does_not_exist_is_bad_input(cli, tmp_path):
    for argv in (("boson-info",), ("boson-raw", "0x00050002"), ("boson-config", "--slave")):
        code, _, err = cli(*argv, "--port", str(tmp_path / "ttyACM9"), *FAST)
        assert code == 2 and "no such port" in err, argv


@pytest.mark.slow
def test_info_prints_no_empty_table_when_every_camera_fails(cli, pair):
    for emu in pair:
        emu.faults = parse_faults("stall")
    code, out, err = cli("boson-info", *FAST)
    assert code == 1 and out == "" and err.count("no reply") == 2


def test_restore_without_persist_warns_that_flash_keeps_the_old_settings(cli, make_boson):
    emu = make_boson(LEFT)
    code, _, err = cli("boson-restore-defaults", "--yes", *FAST)
    assert code == 0 and "flash not written" in err and emu.state.flash_writes == 0
