"""Derived values: the sensor frames, the estimates list, the exports of the description."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from platform_tools.rig.frames import T_BODY_OPTICAL
from platform_tools.rig import load_rig


def test_frames_follow_the_description(rig):
    d = rig.desc
    zed_b = rig.dim(d.sensors.zed_x.part, "baseline_mm")
    np.testing.assert_allclose(rig.T("zed_x_left", "zed_x_right").t, [0, -zed_b, 0], atol=1e-9)
    np.testing.assert_allclose(rig.T("thermal_left", "thermal_right").t, [0, -d.sensors.thermal.baseline_mm, 0],
                               atol=1e-9)
    # thermal pair below the ZED, as in the paper
    assert rig.frame("thermal_left").t[2] < rig.frame("zed_x_left").t[2]
    # optical frames are the body frames turned by the fixed optical rotation
    for side in ("left", "right"):
        for cam in ("zed_x", "thermal"):
            assert rig.frame(f"{cam}_{side}_optical").isclose(rig.frame(f"{cam}_{side}") @ T_BODY_OPTICAL)


def test_pitched_pair_moves_optical_axes(rig):
    tilted = load_rig(overrides=["sensors.thermal.pose.rpy_deg[1]=10"])  # pitch down 10 deg (y left, +pitch = nose down)
    z_axis = tilted.frame("thermal_left_optical").rotate([0, 0, 1])
    assert z_axis[2] == pytest.approx(-np.sin(np.radians(10)), abs=1e-9)


def test_estimates_list_names_key_paths(rig):
    paths = {e.path for e in rig.estimates()}
    assert "parts.zed_x.envelope_mm.x" in paths          # an estimate
    assert "parts.zed_x.dims.baseline_mm" not in paths   # a datasheet value
    assert "parts.boson_640.mounting[0]" in paths        # mounting holes not found in public text
    # measuring a value removes it from the list
    measured = load_rig(overrides=["parts.zed_x.envelope_mm.x.confidence=measured"])
    assert "parts.zed_x.envelope_mm.x" not in {e.path for e in measured.estimates()}


def test_thermal_module_width(rig):
    hs = rig.desc.enclosure.heat_sink
    body = rig.part("boson_640").envelope_mm.y.value
    assert rig.thermal_module_width_mm() == pytest.approx(body + 2 * (hs.wall_mm + hs.fin_height_mm))


@pytest.mark.slow
def test_export_writes_real_formats(tmp_path: Path, platform_tools, rig):
    vnlog = pytest.importorskip("vnlog")
    out = tmp_path / "rig"
    r = platform_tools("rig", "export", "--out", str(out))
    assert r.returncode == 0, r.stderr
    resolved = yaml.safe_load((out / "rig.resolved.yaml").read_text())
    assert resolved["sensors"]["thermal"]["baseline_mm"] == rig.desc.sensors.thermal.baseline_mm
    doc = json.loads((out / "rig.resolved.json").read_text())
    assert doc["derived"]["hash"] == rig.hash
    # frames.vnl reads back with the vnlog parser that mrcal's tools use
    parser, rows = vnlog.vnlog(), []
    with open(out / "frames.vnl") as f:
        for line in f:
            parser.parse(line)
            if parser.values_dict():
                rows.append(parser.values_dict())
    assert [r["frame"] for r in rows] == list(rig.sensor_frames())
    left = next(r for r in rows if r["frame"] == "thermal_left_optical")
    T = rig.frame("thermal_left_optical")
    assert float(left["y_mm"]) == pytest.approx(T.t[1], abs=1e-6)
    q = [float(left[k]) for k in ("qx", "qy", "qz", "qw")]
    np.testing.assert_allclose(q, T.quaternion(), atol=1e-6)


@pytest.mark.slow
def test_export_to_unwritable_folder_exit_2(platform_tools):
    r = platform_tools("rig", "export", "--out", "/sys/rgbt-rig")  # refused even to root
    assert r.returncode == 2, r.stderr
    assert "/sys/rgbt-rig: cannot write" in r.stderr and "Traceback" not in r.stderr


@pytest.mark.slow
def test_export_into_a_file_path_exit_2(tmp_path: Path, platform_tools):
    f = tmp_path / "afile"
    f.write_text("x")
    r = platform_tools("rig", "export", "--out", str(f / "rig"))
    assert r.returncode == 2, r.stderr
    assert "afile" in r.stderr and "Traceback" not in r.stderr
    assert f.read_text() == "x"


def test_sensor_frames_are_computed_once_and_handed_out_as_a_new_dict():
    """The frames are computed once per rig (the firmware's render asks 108 times), but each call gets its own dict:
    what one caller removes the next still gets; another rig (another override) has its own frames."""
    rig = load_rig()
    first = rig.sensor_frames()
    del first["thermal_left"]
    again = rig.sensor_frames()
    assert "thermal_left" in again and again is not first
    assert again["zed_x"] is rig.sensor_frames()["zed_x"]
    wider = load_rig(overrides=["sensors.thermal.baseline_mm=130"])
    assert wider.frame("thermal_left").t[1] - rig.frame("thermal_left").t[1] == pytest.approx(
        (130 - rig.desc.sensors.thermal.baseline_mm) / 2)
