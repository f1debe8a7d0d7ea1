"""doctor's Boson checks (firmware/device/bosonprobe.py) against emulated cameras on ptys: the telemetry
rows must be on and where the FFC decoder reads them, since every recording's FFC status comes from there."""
from __future__ import annotations

import pytest

from firmware.device import bosonprobe
from platform_tools.boson import commands as C
from platform_tools.boson.emulator.state import FACTORY
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
    assert "right has its rows at the top" in check.detail and "left" not in check.detail
