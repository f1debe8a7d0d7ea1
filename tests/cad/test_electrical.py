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


def _rig_with_converter_fuse_limit(tmp_path, rig_text, limit_a):
    """config/rig.yaml with a datasheet input-fuse limit on the converter (parts.dc_converter.dims), as the
    TEP 150WI's page gives one; the file is edited as text so the loader reads it as a user's file."""
    import yaml
    data = yaml.safe_load(rig_text)
    data["parts"]["dc_converter"].setdefault("dims", {})["input_fuse_max_a"] = {
        "value": limit_a, "source": "estimate", "confidence": "estimate"}
    path = tmp_path / "rig.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return load_rig(path)


def test_fuse_against_the_converters_input_fuse_limit(tmp_path, rig_text):
    """A converter whose datasheet caps its input fuse: the rig's fuse passes under the cap and fails above
    it; every other check is unchanged. Without a cap the line says the fuse was not checked against it."""
    fuse_a = load_rig().part("blade_fuse").rating_a.value
    ok = _by_name(_rig_with_converter_fuse_limit(tmp_path, rig_text, 4 * fuse_a))
    assert ok["converter input fuse"].ok and "slow-blow" in ok["converter input fuse"].text
    low = _by_name(_rig_with_converter_fuse_limit(tmp_path, rig_text, fuse_a / 2))
    assert not low["converter input fuse"].ok and "ABOVE" in low["converter input fuse"].text
    assert all(r.ok for n, r in low.items() if n != "converter input fuse")
    plain = _by_name(load_rig())["converter input fuse"]
    dims = load_rig().part("dc_converter").dims
    assert ("not checked" in plain.text) == ("input_fuse_max_a" not in dims)


def test_efficiency_sets_the_battery_current():
    """The battery draws the load through the converter's efficiency (parts.dc_converter.efficiency): a less
    efficient converter draws more from the pack, in proportion."""
    rig = load_rig()
    eff = rig.part("dc_converter").efficiency.value
    worse = load_rig(overrides=[f"parts.dc_converter.efficiency.value={eff * 0.8}"])
    a, b = budget(rig, COUNTS), budget(worse, COUNTS)
    assert b.load_w == pytest.approx(a.load_w)
    assert b.battery_w == pytest.approx(a.battery_w / 0.8) and b.battery_a == pytest.approx(a.battery_a / 0.8)


def _rig_with_led(tmp_path, rig_text, **dims):
    """config/rig.yaml with the record button's LED figures in its dims (edited as text, as a user's file)."""
    import yaml
    data = yaml.safe_load(rig_text)
    for k, v in dims.items():
        data["parts"]["record_button"].setdefault("dims", {})[k] = {"value": v, "source": "estimate", "confidence": "estimate"}
    path = tmp_path / "rig.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return load_rig(path)


def test_an_led_drawing_more_than_the_gpio_may_source_fails(tmp_path, rig_text):
    """A red LED (2.0 V) on a 100 ohm resistor draws 13 mA from the 3.3 V pin, far over what the header's level
    shifter may source: one line saying so, naming the pin's figure and asking for a transistor; every other
    electrical check is unchanged. On a 47 kOhm resistor (0.03 mA) it passes; switched by a transistor rated
    over its current it passes too, under the transistor's rating it fails."""
    from cad.electrical import GPIO_SOURCE_MAX_MA
    res = _by_name(_rig_with_led(tmp_path, rig_text, led_forward_v=2.0, led_series_resistor_ohm=100))
    r = res["button LED current"]
    assert not r.ok and len(r.text.splitlines()) == 1, r.text
    assert "13.00 mA" in r.text and f"{GPIO_SOURCE_MAX_MA:.3f} mA" in r.text and "transistor" in r.text, r.text
    assert "TXB0108" in r.text and "pin 31" in r.text
    assert all(x.ok for n, x in res.items() if n != "button LED current")
    assert (1.3 / 100 * 1000) > GPIO_SOURCE_MAX_MA
    weak = _by_name(_rig_with_led(tmp_path, rig_text, led_forward_v=2.0, led_series_resistor_ohm=47000))
    assert weak["button LED current"].ok, weak["button LED current"].text
    driven = _by_name(_rig_with_led(tmp_path, rig_text, led_forward_v=2.0, led_series_resistor_ohm=100,
                                    led_driver_max_ma=100))["button LED current"]
    assert driven.ok and "driver" in driven.text, driven.text
    small = _by_name(_rig_with_led(tmp_path, rig_text, led_forward_v=2.0, led_series_resistor_ohm=100,
                                   led_driver_max_ma=5))["button LED current"]
    assert not small.ok and "OVER its rating" in small.text


def test_an_led_without_its_figures_says_its_current_was_not_checked():
    r = _by_name(load_rig())["button LED current"]
    assert r.ok and "NOT checked" in r.text and "led_series_resistor_ohm" in r.text and "transistor" in r.text
