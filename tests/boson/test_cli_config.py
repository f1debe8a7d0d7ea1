"""`platform_tools boson-config` run for real against two emulated Bosons over ptys."""
from __future__ import annotations

import pytest

import json

from platform_tools.boson import commands as C
from platform_tools.boson.emulator import parse_faults

from .conftest import FAST, LEFT, RIG_SERIALS, RIGHT

SLAVE, MASTER, DISABLE = (int(C.ExtSyncMode.SLAVE), int(C.ExtSyncMode.MASTER), int(C.ExtSyncMode.DISABLE))


def config(cli, *extra):
    code, out, err = cli("boson-config", *RIG_SERIALS, *FAST, "--json", *extra)
    return code, (json.loads(out) if out.strip() else None), err


def by_label(doc):
    return {c["label"]: c for c in doc["cameras"]}


def sets(emu):
    return emu.state.settings["ext_sync_mode"]


def test_slave_on_both_cameras_then_idempotent(cli, pair):
    left, right = pair
    code, doc, _ = config(cli, "--slave")
    assert code == 0 and doc["ok"] and doc["mode"] == "slave" and not doc["persist"]
    cams = by_label(doc)
    assert cams["left"]["serial"] == LEFT and cams["right"]["serial"] == RIGHT
    for cam in cams.values():
        assert cam["status"] == "configured"
        # slave mode, and the telemetry rows the FFC status is read from (the rig records them)
        assert cam["changes"] == [{"setting": "ext_sync_mode", "from": "disable", "to": "slave"},
                                  {"setting": "telemetry_location", "from": "top", "to": "bottom"},
                                  {"setting": "telemetry_state", "from": "disabled", "to": "enabled"}]
        assert cam["after"] == {"ext_sync_mode": "slave", "telemetry_location": "bottom",
                                "telemetry_packing": "default", "telemetry_state": "enabled"}
    assert sets(left) == sets(right) == SLAVE
    for emu in (left, right):   # rows placed where platform_tools.boson.telemetry reads them, before switching on
        assert emu.state.settings["telemetry_location"] == C.TelemetryLocation.BOTTOM
        assert emu.state.settings["telemetry_state"] == C.TelemetryState.ENABLED
    assert left.state.flash["ext_sync_mode"] == DISABLE and left.state.flash_writes == 0   # not persisted
    requests = left.requests
    code, doc, _ = config(cli, "--slave")
    assert code == 0 and all(c["status"] == "unchanged" and c["changes"] == [] for c in doc["cameras"])
    # the serial (identity, asked once), then sync mode, telemetry location, packing and state: that read
    # finds nothing to change, so it is both the verification and the final state
    assert left.requests - requests == 1 + 4
    assert all(c["flash"] is None for c in doc["cameras"])        # slave, not persisted: flash not read


def test_telemetry_left_alone_when_the_rig_records_none(cli, pair):
    left, _ = pair
    code, doc, _ = config(cli, "--slave", "--set", "on_device.thermal_telemetry_rows=0")
    assert code == 0
    assert by_label(doc)["left"]["changes"] == [{"setting": "ext_sync_mode", "from": "disable", "to": "slave"}]
    assert left.state.settings["telemetry_state"] == C.TelemetryState.DISABLED


@pytest.mark.slow
def test_mode_defaults_to_the_rig_description(cli, pair):
    code, doc, _ = config(cli, "--set", "sync.boson_mode=master")
    assert code == 0 and doc["mode"] == "master" and sets(pair[0]) == MASTER


def test_dry_run_writes_nothing(cli, pair):
    code, doc, _ = config(cli, "--slave", "--dry-run")
    assert code == 0 and all(c["status"] == "would-change" for c in doc["cameras"])
    assert sets(pair[0]) == sets(pair[1]) == DISABLE


def test_table_output(cli, pair):
    code, out, err = cli("boson-config", "--slave", *RIG_SERIALS, *FAST)
    assert code == 0
    assert "left" in out and "configured" in out and "ext_sync_mode: disable -> slave" in out


@pytest.mark.slow
def test_persist_warns_writes_flash_and_survives_reboot(cli, pair):
    left, right = pair
    code, doc, err = config(cli, "--slave", "--persist", "--reboot-verify")
    assert code == 0, err
    assert "no video" in err and doc["warnings"]
    for emu in pair:   # one reboot to read the flash, one to verify it
        assert emu.state.flash["ext_sync_mode"] == SLAVE and emu.state.boots == 3 and emu.state.flash_writes == 1
    assert all(c["persisted"] and "rebooted" in c["steps"] and "rebooted to read flash" in c["steps"]
               for c in doc["cameras"])
    assert all(c["flash_before"]["ext_sync_mode"] == "disable" and c["flash"]["ext_sync_mode"] == "slave"
               for c in doc["cameras"])
    # flash only when needed: a second run finds flash holding the wanted settings and writes nothing
    code, doc, err = config(cli, "--slave", "--persist")
    assert code == 0, err
    assert all(c["status"] == "unchanged" and "flash already holds the wanted settings: not written" in c["steps"]
               for c in doc["cameras"])
    assert all(emu.state.flash_writes == 1 for emu in pair)


@pytest.mark.slow
def test_soft_flash_error_is_a_warning_when_read_back_is_right(cli, make_boson):
    emu = make_boson(LEFT, flash_write_status=0x201)
    code, doc, _ = config(cli, "--camera", "left", "--slave", "--persist")
    assert code == 0
    assert "flash write reported FlrError" in doc["cameras"][0]["warnings"][0]


@pytest.mark.slow
def test_check_trigger_passes_with_the_trigger_running(cli, pair, trigger):
    trigger.start()
    code, doc, _ = config(cli, "--slave", "--check-trigger", "--check-seconds", "0.3")
    assert code == 0
    for cam in doc["cameras"]:
        assert 22 <= cam["frame_rate_hz"] <= 38


@pytest.mark.slow
def test_check_trigger_reverts_when_no_frames_arrive(cli, pair):
    left, right = pair
    right.state.settings["ext_sync_mode"] = MASTER
    code, doc, err = config(cli, "--slave", "--check-trigger", "--check-seconds", "0.2")
    assert code == 1
    cams = by_label(doc)
    assert cams["left"]["status"] == cams["right"]["status"] == "reverted"
    assert cams["left"]["frame_rate_hz"] == 0
    assert "expected 30 Hz" in cams["left"]["error"]
    assert sets(left) == DISABLE and sets(right) == MASTER   # each back to what it had
    assert "left: reverted" in err and len([l for l in err.splitlines() if "error:" in l]) == 2


@pytest.mark.slow
def test_check_trigger_failure_after_persist_is_never_written(cli, pair):
    code, doc, _ = config(cli, "--slave", "--check-trigger", "--check-seconds", "0.2", "--persist")
    assert code == 1
    for emu in pair:                                  # the trigger check runs before the flash write
        assert emu.state.flash_writes == 0 and emu.state.flash["ext_sync_mode"] == DISABLE


@pytest.mark.slow
def test_one_dead_camera_leaves_the_other_untouched(cli, pair):
    left, right = pair
    right.faults = parse_faults("stall")
    code, doc, err = config(cli, "--slave")
    assert code == 1
    cams = by_label(doc)
    assert cams["left"]["status"] == "aborted" and "right failed at the read step" in cams["left"]["error"]
    assert cams["right"]["status"] == "error" and "no reply" in cams["right"]["error"]
    assert sets(left) == DISABLE and sets(right) == DISABLE
    assert "error: right: no reply" in err


@pytest.mark.slow
def test_a_camera_failing_at_the_read_step_aborts_the_other(cli, pair):
    left, right = pair
    right.faults = parse_faults(f"stall:fid=0x{C.GET_EXT_SYNC.function_id:08X}")
    code, doc, err = config(cli, "--slave")
    assert code == 1
    cams = by_label(doc)
    assert cams["left"]["status"] == "aborted" and "right failed at the read step" in cams["left"]["error"]
    assert cams["right"]["status"] == "error" and "no reply" in cams["right"]["error"]
    assert sets(left) == DISABLE and sets(right) == DISABLE


def test_failure_mid_apply_reverts_the_camera(cli, pair):
    left, right = pair
    # the second write (display mode) is refused: the first (sync mode) must be undone
    right.faults = parse_faults(f"busy:fid=0x{C.SET_DISPLAY_MODE.function_id:08X}")
    code, doc, _ = config(cli, "--slave", "--display-mode", "one-shot")
    assert code == 1
    cams = by_label(doc)
    assert cams["left"]["status"] == "reverted" and "right failed at the apply step" in cams["left"]["error"]
    assert cams["right"]["status"] == "reverted" and "CamBusy" in cams["right"]["error"]
    assert "set ext_sync_mode slave" in cams["right"]["steps"] and "reverted" in cams["right"]["steps"]
    for emu in pair:                                   # both back to what they had
        assert sets(emu) == DISABLE and emu.state.settings["display_mode"] == 0
        assert emu.state.settings["telemetry_state"] == 0 and emu.state.settings["telemetry_location"] == 0


@pytest.mark.slow
def test_reboot_in_the_middle_of_the_set_command(cli, pair):
    left, right = pair
    left.faults = parse_faults(f"reboot:fid=0x{C.SET_EXT_SYNC.function_id:08X}:times=1")
    code, doc, err = config(cli, "--slave")
    assert code == 0, err
    assert left.state.boots == 2 and sets(left) == SLAVE and sets(right) == SLAVE


@pytest.mark.slow
def test_reboot_after_apply_loses_ram_and_is_reapplied(cli, pair):
    left, _ = pair
    # reboot while reading back: RAM reloads from flash (DISABLE); the tool notices and applies again.
    # Request 9 is the read-back: the serial (identity, asked once), 4 reads, set sync, telemetry location,
    # telemetry state (packing is already the default) = 8 requests, then the first read-back.
    left.faults = parse_faults(f"reboot:fid=0x{C.GET_EXT_SYNC.function_id:08X}:n=9")
    code, doc, err = config(cli, "--slave")
    assert code == 0, err
    cam = by_label(doc)["left"]
    assert left.state.boots == 2 and sets(left) == SLAVE
    assert "re-enumerated" in cam["warnings"][0]


@pytest.mark.slow
def test_noisy_link_still_configures(cli, pair):
    for emu in pair:
        emu.faults = parse_faults("split,garbage:p=0.3,wrongseq:p=0.3,badcrc:p=0.2,busy:p=0.2")
    code, doc, err = config(cli, "--slave", "--retries", "6")
    assert code == 0, err
    assert all(sets(e) == SLAVE for e in pair)


def test_camera_left_needs_the_rig_serial(cli, pair):
    code, out, err = cli("boson-config", "--slave", "--camera", "left", *FAST)
    assert code == 2 and out == ""
    assert "sensors.thermal.left.serial" in err and "--set" in err and len(err.strip().splitlines()) == 1
    assert sets(pair[0]) == DISABLE


@pytest.mark.slow
def test_unknown_serial_lists_what_was_found(cli, pair):
    code, _, err = cli("boson-config", "--slave", "--camera", "12345", *FAST)
    assert code == 2 and "SN 12345" in err and f"SN {LEFT}" in err and f"SN {RIGHT}" in err


def test_rig_camera_missing_is_refused_before_touching_the_other(cli, make_boson):
    left = make_boson(LEFT)
    code, _, err = cli("boson-config", "--slave", *RIG_SERIALS, *FAST)
    assert code == 2 and f"right camera (SN {RIGHT}) not found" in err and f"SN {LEFT}" in err
    assert sets(left) == DISABLE and left.requests == 1      # asked its serial number, nothing else


def test_no_camera(cli, by_id):
    code, out, err = cli("boson-config", "--slave", *FAST)
    assert code == 2 and "no Boson found" in err and out == ""


def test_identity_mismatch_on_an_explicit_port(cli, make_boson):
    emu = make_boson(LEFT)
    code, doc, _ = config(cli, "--slave", "--port", emu.port, "--camera", "right")
    assert code == 1 and "not SN" in doc["cameras"][0]["error"] and sets(emu) == DISABLE


def test_port_that_does_not_exist(cli, tmp_path):
    code, doc, err = config(cli, "--slave", "--port", str(tmp_path / "ttyACM9"))
    assert code == 2 and "no such port" in err and doc["cameras"][0]["port_problem"]


@pytest.mark.slow
def test_bad_options(cli, pair):
    assert cli("boson-config", "--slave", "--reboot-verify", *FAST)[0] == 2
    assert cli("boson-config", "--master", "--check-trigger", *FAST)[0] == 2
    assert cli("boson-config", "--slave", "--timeout", "0")[0] == 2
    assert cli("boson-config", "--slave", "--set", "sync.boson_mode=sideways")[0] == 2
