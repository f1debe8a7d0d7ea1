"""The thermal driver leaves the Bosons alone (issue 18, item 3): no V4L2 control written unless the rig asks,
the guard that refuses the rest, camera_info from the calibration or the nominal model."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from firmware import camerainfo, v4l2
from firmware.checks import FAILED, OK
from firmware.device import v4l2guard
from firmware.render import write
from platform_tools.rig import load_rig

SERIALS = ("sensors.thermal.left.serial=93588", "sensors.thermal.right.serial=93599")
THERMAL = ["thermal_left", "thermal_right"]


def render(tmp_path, *extra):
    rig = load_rig(None, [*SERIALS, *extra])
    out = tmp_path / "fw"
    write(rig, out)
    return rig, out


def params(folder: Path, name="thermal_left") -> dict:
    return yaml.safe_load((folder / "config" / f"{name}.yaml").read_text())["/**"]["ros__parameters"]


def set_param(folder: Path, key, value, name="thermal_left") -> None:
    f = folder / "config" / f"{name}.yaml"
    doc = yaml.safe_load(f.read_text())
    if value is None:
        doc["/**"]["ros__parameters"].pop(key)
    else:
        doc["/**"]["ros__parameters"][key] = value
    f.write_text(yaml.safe_dump(doc))


@pytest.mark.slow
def test_default_render_writes_no_control_and_mounts_the_guard(tmp_path):
    rig, folder = render(tmp_path)
    p = params(folder)
    assert all(p[n] == -1 for n, c in v4l2.CONTROLS.items() if c.kind is int)
    assert v4l2.check_controls(folder, rig, THERMAL).status == OK
    compose = yaml.safe_load((folder / "compose.yaml").read_text())["services"]
    assert "./bin/v4l2-ctl:/usr/local/bin/v4l2-ctl:ro" in compose["thermal_right"]["volumes"]
    assert "--allow ''" in (folder / "bin" / "v4l2-ctl").read_text()


@pytest.mark.slow
@pytest.mark.parametrize("key,value,message", [
    ("brightness", 50, "brightness 50 writes brightness"),
    ("brightness", None, "brightness unset (usb_cam default) writes brightness"),
    ("gain", 3, "gain 3 writes gain"),
])
def test_a_config_writing_an_unasked_integer_control_fails(tmp_path, key, value, message):
    rig, folder = render(tmp_path)
    set_param(folder, key, value)
    c = v4l2.check_controls(folder, rig, THERMAL)
    assert c.status == FAILED and message in c.detail and "thermal_left.yaml" in c.detail


@pytest.mark.slow
def test_without_the_guard_the_boolean_controls_fail(tmp_path):
    rig, folder = render(tmp_path)
    doc = yaml.safe_load((folder / "compose.yaml").read_text())
    doc["services"]["thermal_right"]["volumes"] = [v for v in doc["services"]["thermal_right"]["volumes"]
                                                   if "v4l2-ctl" not in v]
    (folder / "compose.yaml").write_text(yaml.safe_dump(doc))
    c = v4l2.check_controls(folder, rig, THERMAL)
    assert c.status == FAILED and "thermal_right: usb_cam writes exposure_auto (autoexposure)" in c.detail
    assert "thermal_left" not in c.detail


@pytest.mark.slow
def test_a_control_the_rig_asks_for_is_rendered_and_allowed(tmp_path):
    rig, folder = render(tmp_path, "on_device.thermal_v4l2_controls={brightness: 30, autoexposure: false}")
    p = params(folder, "thermal_right")
    assert p["brightness"] == 30 and p["autoexposure"] is False and p["contrast"] == -1
    assert v4l2.check_controls(folder, rig, THERMAL).status == OK
    assert "--allow brightness,exposure_auto " in (folder / "bin" / "v4l2-ctl").read_text()


@pytest.mark.slow
@pytest.mark.parametrize("value,message", [
    ("{loudness: 3}", "on_device.thermal_v4l2_controls.loudness: not a usb_cam control parameter"),
    ("{brightness: true}", "on_device.thermal_v4l2_controls.brightness: True is not a non-negative integer"),
    ("{autoexposure: 1}", "on_device.thermal_v4l2_controls.autoexposure: 1 is not a true/false"),
])
def test_a_bad_control_in_the_rig_is_one_line_exit_2(value, message):
    r = subprocess.run([sys.executable, "-m", "platform_tools.cli.main", "firmware", "render", "--out",
                        "/nonexistent/never", "--set", f"on_device.thermal_v4l2_controls={value}"],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and message in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr


# ----------------------------------------------------------------------------- the guard
@pytest.fixture
def real_v4l2_ctl(tmp_path, monkeypatch):
    """A stand-in for /usr/bin/v4l2-ctl that records its arguments."""
    log = tmp_path / "calls"
    real = tmp_path / "v4l2-ctl-real"
    real.write_text(f"#!/bin/sh\necho \"$@\" >> {log}\n")
    real.chmod(0o755)
    monkeypatch.setenv("V4L2_CTL_REAL", str(real))
    return log


def run_guard(allow: str, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "firmware.device.v4l2guard", "--allow", allow, "--", *args],
                          capture_output=True, text=True, timeout=30, env=os.environ)


@pytest.mark.slow
@pytest.mark.parametrize("args", [("--device=/dev/video0", "-c", "exposure_auto=3"),
                                  ("-d", "/dev/video0", "--set-ctrl=gain=50"),
                                  ("-d", "/dev/video0", "-c", "brightness=40,white_balance_temperature_auto=1")])
def test_the_guard_refuses_an_unasked_control_without_touching_the_device(real_v4l2_ctl, args):
    r = run_guard("brightness", *args)
    assert r.returncode == 1 and "refused to set" in r.stderr
    assert not real_v4l2_ctl.exists()


@pytest.mark.slow
def test_the_guard_passes_asked_controls_and_other_calls_through(real_v4l2_ctl):
    assert run_guard("brightness", "--device=/dev/video0", "-c", "brightness=40").returncode == 0
    assert run_guard("", "--list-ctrls").returncode == 0
    assert real_v4l2_ctl.read_text().splitlines() == ["--device=/dev/video0 -c brightness=40", "--list-ctrls"]


def test_controls_set_parses_every_spelling():
    assert v4l2guard.controls_set(["-cfoo=1", "--set-ctrl", "a=1,b=2", "--set-ctrl=c=3", "-d", "x"]) == \
        ["foo", "a", "b", "c"]


@pytest.mark.slow
# ----------------------------------------------------------------------------- camera_info
def test_without_a_calibration_the_nominal_model_is_published(tmp_path):
    rig, folder = render(tmp_path)
    assert params(folder)["camera_info_url"] == "file:///config/thermal_left_camera_info.yaml"
    text = (folder / "config" / "thermal_left_camera_info.yaml").read_text()
    doc = yaml.safe_load(text)
    model = rig.camera_model(rig.desc.sensors.thermal.camera_model)
    assert text.startswith("# nominal model")
    assert doc["camera_matrix"]["data"][0] == pytest.approx(rig.focal_px(model))
    assert (doc["image_width"], doc["image_height"]) == (model.width_px, model.height_px)


def _calibration(tmp_path, width=640, height=512) -> Path:
    f = tmp_path / "cal" / "left.yaml"
    f.parent.mkdir()
    f.write_text(yaml.safe_dump({
        "image_width": width, "image_height": height, "camera_name": "boson", "distortion_model": "plumb_bob",
        "camera_matrix": {"rows": 3, "cols": 3, "data": [411.34, 0, 320.40, 0, 412.67, 251.97, 0, 0, 1]},
        "distortion_coefficients": {"rows": 1, "cols": 5, "data": [-0.3565, 0.1078, 0, 0, 0]},
        "rectification_matrix": {"rows": 3, "cols": 3, "data": [1, 0, 0, 0, 1, 0, 0, 0, 1]},
        "projection_matrix": {"rows": 3, "cols": 4, "data": [411.34, 0, 320.40, 0, 0, 412.67, 251.97, 0, 0, 0, 1, 0]}}))
    return f


@pytest.mark.slow
def test_a_calibration_named_by_the_rig_is_what_is_published(tmp_path):
    cal = _calibration(tmp_path)
    rig, folder = render(tmp_path, f"on_device.thermal_camera_info_left={cal}")
    doc = yaml.safe_load((folder / "config" / "thermal_left_camera_info.yaml").read_text())
    assert doc["camera_matrix"]["data"][0] == 411.34 and doc["camera_name"] == "thermal_left"
    assert camerainfo.render(rig, "left")[1] == f"calibration {cal}"
    assert camerainfo.render(rig, "right")[1] == "nominal"


def test_a_calibration_of_another_size_is_refused_naming_the_key(tmp_path):
    cal = _calibration(tmp_path, 320, 256)
    rig = load_rig(None, [*SERIALS, f"on_device.thermal_camera_info_left={cal}"])
    with pytest.raises(ValueError, match=r"on_device.thermal_camera_info_left: .*320x256, the Boson model is 640x512"):
        camerainfo.render(rig, "left")
