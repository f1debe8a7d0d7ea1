"""The electrical checks (cad.electrical) on the rig description alone: no CAD build."""
from __future__ import annotations

import pytest

from cad.electrical import budget, electrical_checks, sync_check
from platform_tools.rig.loader import load_rig

COUNTS = {"jetson_agx_orin": 1, "zed_x": 1, "boson_640": 2, "zed_link_quad": 1, "fan_3010_5v": 2}


def _by_name(rig):
    return {r.name: r for r in electrical_checks(rig, COUNTS)}


def test_default_rig_passes_and_current_follows_the_parts():
    rig = load_rig()
    assert all(r.ok for r in electrical_checks(rig, COUNTS)), [r.text for r in electrical_checks(rig, COUNTS)]
    b = budget(rig, COUNTS)
    orin = rig.part("jetson_agx_orin").power_w.value
    assert b.load_w > orin
    assert b.battery_a == pytest.approx(b.battery_w / b.cutoff_v) and b.battery_a > b.battery_a_full
    assert b.fuse_a >= 1.25 * b.battery_a
    more = budget(rig, {**COUNTS, "boson_640": 20})   # more load: more current
    assert more.battery_a > b.battery_a


def test_under_rated_switch_fails():
    rig = load_rig(overrides=["parts.power_switch.rating_a.value=6"])
    res = _by_name(rig)
    assert not res["switch rating"].ok and "does not cover" in res["switch rating"].text


def test_fuse_below_the_load_fails():
    res = _by_name(load_rig(overrides=["parts.blade_fuse.rating_a.value=5"]))
    assert not res["fuse rating"].ok


def test_sync_level_outside_the_boson_input_fails():
    assert sync_check(load_rig()).ok
    low = sync_check(load_rig(overrides=["sync.level_v=1.8"]))
    assert not low.ok and "OUTSIDE" in low.text


def test_5v_led_on_the_3v3_gpio_fails():
    res = _by_name(load_rig(overrides=["parts.record_button.supply_v.min=4.5", "parts.record_button.supply_v.max=5.5"]))
    assert not res["button LED voltage"].ok
