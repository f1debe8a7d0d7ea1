"""doctor's Boson checks (firmware/device/bosonprobe.py) against emulated cameras on ptys: the telemetry
rows must be on and where the FFC decoder reads them, since every recording's FFC status comes from there;
left and right are the cameras answering the rig's serials over their serial links, whatever the by-id and
udev names say (swapped, missing, duplicate, unknown), with the physical USB port (by-path) of each."""
from __future__ import annotations

import os
import shlex

import pytest

from firmware.cli import main as rig_device
from firmware.device import bosonprobe
from platform_tools.boson import commands as C
from platform_tools.boson import discovery
from platform_tools.boson.emulator import BosonState, EmulatedBoson
from platform_tools.boson.emulator.state import FACTORY
from platform_tools.boson.syncsetup import SYNC_MODES
from platform_tools.boson.telemetry import EXPECTED_LOCATION
from platform_tools.rig import load_rig
from platform_tools.rig.checks import FAILED, OK

from .conftest import LEFT, RIGHT

CONFIGURED = dict(FACTORY, ext_sync_mode=int(C.ExtSyncMode.SLAVE), telemetry_state=1,
                  telemetry_location=int(C.TelemetryLocation[EXPECTED_LOCATION.upper()]))


@pytest.fixture
def rig():
    return load_rig(overrides=[f"sensors.thermal.left.serial={LEFT}", f"sensors.thermal.right.serial={RIGHT}",
                               "on_device.trigger_watch_s=0.2"])


def telemetry_check(rig, tmp_path) -> dict:
    cameras: dict = {}
    return {c.name: c for c in bosonprobe.checks(rig, tmp_path, cameras)}["telemetry"], cameras


@pytest.mark.slow
def test_telemetry_rows_where_the_decoder_reads_them_pass(rig, make_boson, trigger, tmp_path):
    trigger.start()
    make_boson(LEFT, settings=dict(CONFIGURED)), make_boson(RIGHT, settings=dict(CONFIGURED))
    check, cameras = telemetry_check(rig, tmp_path)
    assert check.status == OK and EXPECTED_LOCATION in check.detail
    assert cameras["left"]["telemetry_location"] == EXPECTED_LOCATION


@pytest.mark.slow
def test_telemetry_rows_at_the_top_fail_naming_the_camera(rig, make_boson, trigger, tmp_path):
    trigger.start()
    make_boson(LEFT, settings=dict(CONFIGURED))
    make_boson(RIGHT, settings=dict(CONFIGURED, telemetry_location=int(C.TelemetryLocation.TOP)))
    check, _ = telemetry_check(rig, tmp_path)
    assert check.status == FAILED
    problem = check.detail.split("`")[0]                    # the command named after it has the rig's overrides
    assert "right has its rows at the top" in problem and "left" not in problem
    # the fix named is the device's own command (the images install no platform_tools), with the rig's mode
    assert "run `rig-device boson-config --slave " in check.detail and "platform_tools" not in check.detail


@pytest.mark.slow
@pytest.mark.parametrize("mode,flag", [("master", "--master"), ("disabled", "--no-sync")])
def test_a_wrong_sync_mode_names_the_device_command_that_fixes_it(make_boson, trigger, tmp_path, capsys, mode,
                                                                  flag):
    rig = load_rig(overrides=[f"sensors.thermal.left.serial={LEFT}", f"sensors.thermal.right.serial={RIGHT}",
                              "on_device.trigger_watch_s=0.2", f"sync.boson_mode={mode}"])
    trigger.start()
    pair = make_boson(LEFT, settings=dict(CONFIGURED)), make_boson(RIGHT, settings=dict(CONFIGURED))  # both slave
    check = doctor_checks(rig, tmp_path)[0]["sync mode"]
    assert check.status == FAILED and "left is " in check.detail and "right is " in check.detail
    argv = shlex.split(check.detail.split("`")[1])
    assert argv[:3] == ["rig-device", "boson-config", flag] and check.detail.endswith("`")
    # run as named, it is all a user needs: the same rig (file, overrides, udev folder), then doctor passes
    assert rig_device(argv[1:]) == 0, capsys.readouterr().err
    assert all(emu.state.settings["ext_sync_mode"] == SYNC_MODES[mode] for emu in pair)
    assert doctor_checks(rig, tmp_path)[0]["sync mode"].status == OK


# ----------------------------------------------------------------------------- which camera is which
@pytest.fixture
def linked(by_id, trigger, tmp_path, monkeypatch):
    """linked({link name in by-id: camera serial}, by_path={camera serial: USB port name}) -> emulated
    cameras (configured, trigger running) whose by-id links are made here, as udev would name them (a USB
    serial string that is not the camera's serial included), and by-path links for the serials given."""
    folder = tmp_path / "by-path"
    folder.mkdir()
    monkeypatch.setenv(discovery.BY_PATH_ENV, str(folder))
    started = []

    def make(names: dict[str, int], by_path: dict[int, str] | None = None):
        trigger.start()
        emus = {}
        for usb, sn in names.items():
            emu = EmulatedBoson(BosonState(sn, trigger=trigger, settings=dict(CONFIGURED)), by_id_dir=None,
                                seed=sn).start()
            started.append(emu)
            os.symlink(emu.path, by_id / f"usb-FLIR_Boson_{usb}-if00")
            if sn in (by_path or {}):
                os.symlink(emu.path, folder / by_path[sn])
            emus[usb] = emu
        return emus
    yield make
    for emu in started:
        emu.stop()


def doctor_checks(rig, dev_dir) -> tuple[dict, dict]:
    cameras: dict = {}
    return {c.name: c for c in bosonprobe.checks(rig, dev_dir, cameras)}, cameras


@pytest.mark.slow
def test_each_camera_is_found_by_the_serial_it_answers_and_its_usb_port_named(rig, linked, tmp_path):
    linked({str(LEFT): LEFT, str(RIGHT): RIGHT, "55555": 55555},
           by_path={LEFT: "platform-3610000.usb-usb-0:1.2:1.0", RIGHT: "platform-3610000.usb-usb-0:1.3:1.0"})
    checks, cameras = doctor_checks(rig, tmp_path)
    cam = checks["thermal cameras"]
    assert cam.status == OK, cam.detail
    assert f"left SN {LEFT}" in cam.detail and "USB port platform-3610000.usb-usb-0:1.2:1.0" in cam.detail
    assert cameras["right"]["by_path"].endswith("usb-0:1.3:1.0") and cameras["right"]["serial"] == RIGHT
    assert "holds SN 55555, which the rig does not name" in cam.detail      # an unknown camera: a note
    assert checks["telemetry"].status == OK


@pytest.mark.slow
def test_swapped_usb_strings_fail_naming_the_port_and_the_camera_it_really_holds(rig, linked, tmp_path):
    linked({str(RIGHT): LEFT, str(LEFT): RIGHT})          # each link's USB string names the other camera
    checks, cameras = doctor_checks(rig, tmp_path)
    cam = checks["thermal cameras"]
    assert cam.status == FAILED
    assert (f"left camera (SN {LEFT}) is on " in cam.detail and f"usb-FLIR_Boson_{RIGHT}-if00" in cam.detail
            and f"names the right camera's SN {RIGHT}" in cam.detail)
    assert cameras["left"]["serial"] == LEFT and cameras["left"]["port"].endswith(f"usb-FLIR_Boson_{RIGHT}-if00")


@pytest.mark.slow
def test_a_udev_name_leading_to_the_other_camera_fails(rig, linked, tmp_path):
    emus = linked({str(LEFT): LEFT, str(RIGHT): RIGHT})
    dev = tmp_path / "dev"
    dev.mkdir()
    os.symlink(emus[str(RIGHT)].path, dev / rig.boson_device_nodes("left")["serial"])     # swapped rule
    os.symlink(emus[str(RIGHT)].path, dev / rig.boson_device_nodes("right")["serial"])
    checks, _ = doctor_checks(rig, dev)
    cam = checks["thermal cameras"]
    assert cam.status == FAILED
    name = rig.boson_device_nodes("left")["serial"]
    assert f"udev name {name} leads to the camera answering SN {RIGHT}, not to the left camera" in cam.detail
    assert rig.boson_device_nodes("right")["serial"] not in cam.detail        # the right one is right


@pytest.mark.slow
def test_a_missing_camera_fails_naming_what_every_port_answered(rig, linked, tmp_path):
    linked({str(LEFT): LEFT, "77": 77777})
    checks, cameras = doctor_checks(rig, tmp_path)
    cam = checks["thermal cameras"]
    assert cam.status == FAILED and f"right camera (SN {RIGHT}) not found" in cam.detail
    assert "usb-FLIR_Boson_77-if00 (USB serial 77) answers SN 77777" in cam.detail
    assert set(cameras) == {"left"}                     # the camera that is there is still checked


@pytest.mark.slow
def test_two_ports_answering_one_serial_fail_naming_both(rig, linked, tmp_path):
    linked({"1": LEFT, "2": LEFT, str(RIGHT): RIGHT})
    checks, cameras = doctor_checks(rig, tmp_path)
    cam = checks["thermal cameras"]
    assert cam.status == FAILED and f"SN {LEFT} is answered on 2 ports" in cam.detail
    assert "usb-FLIR_Boson_1-if00" in cam.detail and "usb-FLIR_Boson_2-if00" in cam.detail
    assert set(cameras) == {"right"}
