"""`boson-config` as one transaction over both cameras: each fault injected on either camera at each step
(read, apply, verify, trigger check, persist, reboot in the middle of a command), then both emulators'
RAM and flash read straight from their state (not from what the tool reports): either both cameras hold
the wanted settings in RAM and flash, or both hold exactly what they held before, RAM and flash each."""
from __future__ import annotations

import json

import pytest

from platform_tools.boson import commands as C
from platform_tools.boson.emulator import parse_faults
from platform_tools.boson.emulator.state import FACTORY

from .conftest import FAST, LEFT, RIG_SERIALS, RIGHT

KEYS = ("ext_sync_mode", "telemetry_location", "telemetry_packing", "telemetry_state")
WANTED = {"ext_sync_mode": int(C.ExtSyncMode.SLAVE), "telemetry_location": int(C.TelemetryLocation.BOTTOM),
          "telemetry_packing": int(C.TelemetryPacking.DEFAULT), "telemetry_state": int(C.TelemetryState.ENABLED)}
NAMES = {"ext_sync_mode": C.ExtSyncMode, "telemetry_location": C.TelemetryLocation,
         "telemetry_packing": C.TelemetryPacking, "telemetry_state": C.TelemetryState}


def fid(cmd: C.Command) -> str:
    return f"0x{cmd.function_id:08X}"


#: step -> (fault rules on the faulty camera, or "unwired": its trigger input is not connected)
FAULTS = {
    "read": f"stall:fid={fid(C.GET_TELEMETRY_LOCATION)}",
    "apply": f"busy:fid={fid(C.SET_EXT_SYNC)}",
    "verify": f"ignore:fid={fid(C.SET_TELEMETRY)}",          # answers OK, the setting does not stick
    "trigger check": "unwired",
    "persist": f"stall:fid={fid(C.WRITE_FLASH)}:times=3",     # every attempt of the first flash write lost
}
#: a reboot (port gone, command lost, RAM back from flash) in the middle of a command of each step
REBOOTS = {
    "read": f"reboot:fid={fid(C.GET_TELEMETRY_LOCATION)}:times=1",
    "apply": f"reboot:fid={fid(C.SET_TELEMETRY_LOCATION)}:times=1",
    # request 17: the read-back after applying (identity 1, RAM 2-5, reboot 6, serial 7, flash 8-11,
    # three writes 12-14, their read-backs 15-17)
    "verify": f"reboot:fid={fid(C.GET_TELEMETRY)}:n=17",
    "trigger check": f"reboot:fid={fid(C.GET_FRAME_COUNT)}:times=1",
    "persist": f"reboot:fid={fid(C.WRITE_FLASH)}:times=1",
}


def snapshot(emu) -> dict:
    return {"ram": {k: emu.state.settings[k] for k in KEYS}, "flash": {k: emu.state.flash[k] for k in KEYS}}


def start_pair(make_boson, trigger):
    """Left at factory settings; right with MASTER in RAM and flash and, in RAM only, the telemetry rows
    at the bottom (RAM and flash differ: the revert must restore each exactly)."""
    left = make_boson(LEFT)
    right_settings = dict(FACTORY, ext_sync_mode=int(C.ExtSyncMode.MASTER))
    right = make_boson(RIGHT, settings=dict(right_settings, telemetry_location=1), flash=dict(right_settings))
    trigger.start()
    return {"left": left, "right": right}


def run_config(cli):
    code, out, err = cli("boson-config", *RIG_SERIALS, *FAST, "--json", "--slave", "--check-trigger",
                         "--check-seconds", "0.2", "--persist")
    assert out.strip(), f"exit {code}, no JSON: {err}"
    return code, json.loads(out), err


def assert_all_or_nothing(code, doc, emus, before):
    after = {side: snapshot(emu) for side, emu in emus.items()}
    all_new = all(s["ram"] == WANTED and s["flash"] == WANTED for s in after.values())
    all_old = after == before
    assert all_new or all_old, f"half-configured: before {before}, after {after}"
    assert (code == 0) == all_new
    for cam in doc["cameras"]:     # what the tool reports as final state is what the camera holds
        if cam["status"] == "error":           # could not be read at all: nothing written, nothing known
            assert cam["after"] == {} and after[cam["label"]] == before[cam["label"]]
            continue
        ram = after[cam["label"]]["ram"]
        assert cam["after"] == {k: NAMES[k](v).name.lower() for k, v in ram.items()}
        assert cam["status"] in (("configured",) if all_new else ("reverted", "aborted", "error"))
    return all_new


@pytest.mark.slow
@pytest.mark.parametrize("side", ["left", "right"])
@pytest.mark.parametrize("step", list(FAULTS))
def test_a_failure_on_either_camera_at_any_step_leaves_nothing_half_configured(cli, make_boson, trigger, side,
                                                                                step):
    emus = start_pair(make_boson, trigger)
    if FAULTS[step] == "unwired":
        emus[side].state.trigger = None
    else:
        emus[side].faults = parse_faults(FAULTS[step])
    before = {s: snapshot(e) for s, e in emus.items()}
    code, doc, err = run_config(cli)
    assert code == 1
    assert not assert_all_or_nothing(code, doc, emus, before)
    other = "right" if side == "left" else "left"
    assert f"{side} failed at the" in by_label(doc)[other]["error"]
    if step == "persist":                  # the flash this run wrote on the other camera was put back
        assert emus[other].state.flash_writes >= 2


@pytest.mark.slow
@pytest.mark.parametrize("side", ["left", "right"])
@pytest.mark.parametrize("step", list(REBOOTS))
def test_a_reboot_mid_command_on_either_camera_at_any_step_still_configures_both(cli, make_boson, trigger,
                                                                                  side, step):
    emus = start_pair(make_boson, trigger)
    emus[side].faults = parse_faults(REBOOTS[step])
    before = {s: snapshot(e) for s, e in emus.items()}
    code, doc, err = run_config(cli)
    assert code == 0, err
    assert assert_all_or_nothing(code, doc, emus, before)
    extra_boot = emus[side].state.boots - emus["left" if side == "right" else "right"].state.boots
    assert extra_boot == 1                 # the fault fired: one reboot more than the other camera


def by_label(doc):
    return {c["label"]: c for c in doc["cameras"]}


@pytest.mark.slow
def test_no_sync_without_persist_warns_that_flash_still_holds_slave(cli, make_boson):
    slave = dict(FACTORY, ext_sync_mode=int(C.ExtSyncMode.SLAVE))
    emu = make_boson(LEFT, settings=dict(slave), flash=dict(slave))
    code, out, err = cli("boson-config", "--camera", str(LEFT), *FAST, "--json", "--no-sync", "--no-persist",
                         "--set", "on_device.thermal_telemetry_rows=0")
    cam = json.loads(out)["cameras"][0]
    assert code == 0 and cam["status"] == "configured" and emu.state.settings["ext_sync_mode"] == 0
    assert cam["flash"] == {"ext_sync_mode": "slave"} and emu.state.flash_writes == 0
    assert "RAM and flash differ" in err and "ext_sync_mode slave in flash, disable now" in err
