"""--set overrides: validated like the file, unknown keys refused with the closest valid key."""
from __future__ import annotations

import json

import numpy as np
import pytest

from platform_tools.rig import RigError, load_rig


def only_line(info) -> str:
    assert len(info.value.lines) == 1, info.value.lines
    return info.value.lines[0]


def test_override_moves_thermal_cameras():
    base = load_rig()
    rig = load_rig(overrides=["sensors.thermal.baseline_mm=150"])
    assert rig.desc.sensors.thermal.baseline_mm == 150
    np.testing.assert_allclose(rig.frame("thermal_left").t[1], 75.0)
    np.testing.assert_allclose(rig.frame("thermal_right_optical").t[1], -75.0)
    # the ZED X did not move, and the description's identity changed
    assert rig.frame("zed_x_left").isclose(base.frame("zed_x_left"))
    assert rig.hash != base.hash


def test_override_list_item_and_nested_sourced_value():
    rig = load_rig(overrides=["sensors.thermal.pose.xyz_mm[2]=-60", "parts.zed_x.dims.baseline_mm.value=100"])
    np.testing.assert_allclose(rig.frame("thermal_left").t[2], -60.0)
    np.testing.assert_allclose(rig.T("zed_x_right_optical", "zed_x_left_optical").t, [-100.0, 0, 0], atol=1e-9)


def test_override_sets_optional_key_absent_from_file():
    rig = load_rig(overrides=["sensors.thermal.left.serial=93588"])
    assert rig.desc.sensors.thermal.left.serial == 93588


@pytest.mark.slow
@pytest.mark.parametrize("override,words", [
    ("sensors.thermal.baseline=150", ["unknown key sensors.thermal.baseline",
                                      "did you mean sensors.thermal.baseline_mm?"]),
    ("sensor.thermal.baseline_mm=150", ["did you mean sensors?"]),
    ("parts.boson_64.mass_g.value=8", ["unknown key parts.boson_64", "did you mean parts.boson_640?"]),
    ("sensors.thermal.pose.xyz_mm[3]=1", ["index 3 is out of range", "has 3 items"]),
    ("sensors.thermal.baseline_mm", ["expected KEY=VALUE"]),
    ("sensors.thermal.baseline_mm.value=3", ["is a single value"]),
    ("sensors..thermal=1", ["cannot read the key path"]),
])
def test_bad_override_is_one_line(override, words):
    with pytest.raises(RigError) as info:
        load_rig(overrides=[override])
    line = only_line(info)
    assert line.startswith(f"--set {override}"), line
    for w in words:
        assert w in line, (w, line)


@pytest.mark.slow
@pytest.mark.parametrize("override,key,words", [
    ("sensors.thermal.baseline_mm=-150", "sensors.thermal.baseline_mm", ["got -150 mm", "> 0"]),
    ("sensors.thermal.baseline_mm=abc", "sensors.thermal.baseline_mm", ["'abc'", "a number in mm"]),
    ("sensors.thermal.baseline_mm=25", "sensors.thermal.baseline_mm", ["overlap"]),
    ("enclosure.wall_mm=0.2", "enclosure.wall_mm", ["expected >= 0.8 mm"]),
    ("sync.rate_hz=90", "sync.rate_hz", ["at most 60 Hz"]),
])
def test_override_value_validated_like_the_file(override, key, words):
    with pytest.raises(RigError) as info:
        load_rig(overrides=[override])
    line = only_line(info)
    assert line.startswith(f"--set {override}: {key}:"), line
    for w in words:
        assert w in line, (w, line)


@pytest.mark.slow
def test_cli_show_with_override_json(platform_tools):
    r = platform_tools("rig", "show", "--json", "--set", "sensors.thermal.baseline_mm=140")
    assert r.returncode == 0, r.stderr
    doc = json.loads(r.stdout)
    assert doc["rig"]["sensors"]["thermal"]["baseline_mm"] == 140
    frames = {f["frame"]: f for f in doc["derived"]["frames"]}
    assert frames["thermal_left"]["y_mm"] == pytest.approx(70.0)
    assert doc["derived"]["overrides"] == ["sensors.thermal.baseline_mm=140"]


@pytest.mark.slow
def test_cli_bad_override_exit_2(platform_tools):
    r = platform_tools("rig", "show", "--set", "sensors.thermal.baselin_mm=140")
    assert r.returncode == 2
    assert "Traceback" not in r.stderr
    assert "did you mean sensors.thermal.baseline_mm?" in r.stderr
