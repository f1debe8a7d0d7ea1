"""A bad rig file is the first bad input a user makes: every kind gets one clear line naming the file,
the line, the key path, the value and what was expected, and exit code 2 — never a traceback."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

from platform_tools.rig import RigError, load_rig


def edit(text: str, old: str, new: str, count: int = 1) -> str:
    assert text.count(old) >= count, f"test fixture out of date: {old!r} not in config/rig.yaml"
    return text.replace(old, new, count)


# (name, how to break the file, expected key path in the message, words the message must contain)
BROKEN = [
    ("malformed_yaml", lambda t: edit(t, "  wall_mm: 2.4\n", "  wall_mm: [2.4\n"),
     None, ["malformed YAML"]),
    ("missing_key", lambda t: edit(t, "    baseline_mm: 120\n", ""),
     "sensors.thermal.baseline_mm", ["is missing", "a number in mm > 0"]),
    ("wrong_type", lambda t: edit(t, "pose: {xyz_mm: [0, 0, -46]", "pose: {xyz_mm: [0, 0, minus46]"),
     r"sensors.thermal.pose.xyz_mm[2]", ["'minus46'", "a string", "a number in mm"]),
    ("negative_length", lambda t: edit(t, "y: {value: 21, source: boson_groupgets",
                                       "y: {value: -21, source: boson_groupgets"),
     "parts.boson_640.envelope_mm.y.value", ["-21", "> 0"]),
    ("baseline_narrower_than_camera", lambda t: edit(t, "    baseline_mm: 120\n", "    baseline_mm: 20\n"),
     "sensors.thermal.baseline_mm", ["overlap", "expected >="]),
    ("unknown_part_kind", lambda t: edit(t, "kind: thermal_camera", "kind: thermal_cam"),
     "parts.boson_640.kind", ["'thermal_cam'", "did you mean 'thermal_camera'"]),
    ("unknown_key", lambda t: edit(t, "    baseline_mm: 120\n", "    baseline_mm: 120\n    baselin_mm: 120\n"),
     "sensors.thermal.baselin_mm", ["unknown key", "did you mean 'baseline_mm'"]),
    ("wrong_list_length", lambda t: edit(t, "pose: {xyz_mm: [0, 0, -46]", "pose: {xyz_mm: [0, -46]"),
     "sensors.thermal.pose.xyz_mm", ["has 2 items", "3"]),
    ("duplicate_key", lambda t: edit(t, "  wall_mm: 2.4\n", "  wall_mm: 2.4\n  wall_mm: 3.0\n"),
     "enclosure.wall_mm", ["written twice"]),
    ("reference_to_missing_part", lambda t: edit(t, "    part: boson_640\n", "    part: boson_64\n"),
     "sensors.thermal.part", ["'boson_64'", "did you mean 'boson_640'"]),
    ("unknown_source", lambda t: edit(t, "source: fan_model, confidence: measured}", "source: fan_modle, confidence: measured}"),
     "parts.fan_3010_5v.envelope_mm.x.source", ["fan_modle", "not in sources", "did you mean 'fan_model'"]),
    ("unknown_confidence", lambda t: edit(t, "confidence: second_hand, note: \"depth without lens\"",
                                          "confidence: guess, note: \"depth without lens\""),
     "parts.boson_640.envelope_mm.x.confidence", ["'guess'", "datasheet, measured, second_hand, estimate"]),
    ("boolean_for_number", lambda t: edit(t, "  rate_hz: 30\n", "  rate_hz: yes\n"),
     "sync.rate_hz", ["True", "a number in Hz"]),
    ("fits_out_of_order", lambda t: edit(t, "    sliding_mm: 0.25\n", "    sliding_mm: 0.05\n"),
     "printing.fits", ["press < sliding < loose"]),
    ("same_serial_twice", lambda t: edit(edit(t, "      serial: null          #", "      serial: 1234  #"),
                                          "      serial: null\n", "      serial: 1234\n"),
     "sensors.thermal.right.serial", ["same as sensors.thermal.left.serial"]),
    ("wall_thinner_than_printer_allows", lambda t: edit(t, "  wall_mm: 2.4\n", "  wall_mm: 0.5\n"),
     "enclosure.wall_mm", ["0.5", "expected >= 0.8"]),
    ("recording_not_on_data_drive", lambda t: edit(t, "  output_dir: /data/recordings\n", "  output_dir: /home/recordings\n"),
     "recording.output_dir", ["not on the data drive", "eMMC"]),
    ("out_of_range_pin", lambda t: edit(t, "    gpio_pin: 29\n", "    gpio_pin: 41\n"),
     "recording.button.gpio_pin", ["41", "<= 40"]),
    ("unknown_literal", lambda t: edit(t, "  edge: falling\n", "  edge: fallng\n"),
     "sync.edge", ["'fallng'", "did you mean 'falling'"]),
    ("top_level_list", lambda t: "- just\n- a list\n", None, ["expected a YAML mapping"]),
    ("empty_file", lambda t: "", None, ["empty"]),
]


@pytest.mark.slow
@pytest.mark.parametrize("name,breaker,key,words", BROKEN, ids=[b[0] for b in BROKEN])
def test_broken_file_gets_one_clear_line(tmp_path: Path, rig_text: str, name, breaker, key, words):
    bad = tmp_path / "rig.yaml"
    bad.write_text(breaker(rig_text))
    with pytest.raises(RigError) as info:
        load_rig(bad)
    lines = info.value.lines
    assert len(lines) == 1, lines
    line = lines[0]
    assert line.startswith(str(bad)), line
    if key is not None:
        assert f": {key}" in line, line
        # the line number points at the key that is wrong
        m = re.match(re.escape(str(bad)) + r":(\d+)", line)
        assert m, line
        written = bad.read_text().splitlines()[int(m.group(1)) - 1]
        keys = re.findall(r"[A-Za-z_][A-Za-z0-9_]*", key)
        assert any(f"{k}:" in written for k in keys), (line, written)
    for w in words:
        assert w in line, (w, line)


def test_binary_file(tmp_path: Path):
    bad = tmp_path / "rig.yaml"
    bad.write_bytes(b"\x89PNG\r\n\x1a\n\xff\xfe")
    with pytest.raises(RigError, match=r"rig.yaml: not UTF-8 text"):
        load_rig(bad)


def test_missing_file(tmp_path: Path):
    with pytest.raises(RigError, match=r"nope.yaml: no such file"):
        load_rig(tmp_path / "nope.yaml")


def test_several_problems_are_all_reported(tmp_path: Path, rig_text: str):
    text = edit(rig_text, "  wall_mm: 2.4\n", "  wall_mm: -1\n")
    text = edit(text, "  rate_hz: 30\n", "  rate_hz: fast\n")
    bad = tmp_path / "rig.yaml"
    bad.write_text(text)
    with pytest.raises(RigError) as info:
        load_rig(bad)
    keys = sorted(line.split(": ")[1] for line in info.value.lines)
    assert keys == ["enclosure.wall_mm", "sync.rate_hz"]


@pytest.mark.slow
def test_cli_validate_bad_file_exit_2_no_traceback(tmp_path: Path, rig_text: str, platform_tools):
    bad = tmp_path / "rig.yaml"
    bad.write_text(edit(rig_text, "    baseline_mm: 120\n", "    baseline_mm: -5\n"))
    r = platform_tools("rig", "validate", str(bad))
    assert r.returncode == 2
    assert "Traceback" not in r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "sensors.thermal.baseline_mm: got -5 mm; expected a number in mm > 0" in lines[0]


@pytest.mark.slow
def test_cli_validate_json(tmp_path: Path, rig_text: str, platform_tools):
    import json
    bad = tmp_path / "rig.yaml"
    bad.write_text(edit(rig_text, "  edge: falling\n", "  edge: both\n"))
    r = platform_tools("rig", "validate", str(bad), "--json")
    assert r.returncode == 2
    doc = json.loads(r.stdout)
    assert doc["valid"] is False and "sync.edge" in doc["errors"][0]
    ok = platform_tools("rig", "validate", "config/rig.yaml", "--json")
    assert ok.returncode == 0 and json.loads(ok.stdout)["valid"] is True
