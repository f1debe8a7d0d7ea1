"""`doctor --bring-up`: each check passes on a good fake device (emulated Bosons, a fake /etc and /sys, a fake
chronyc, a fake recording) and fails with a clear line on a bad one; unmeasurable ones are skipped, never passed."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from firmware.device import bringup
from platform_tools.boson.telemetry import encode_line, write_into
from platform_tools.rig import load_rig
from platform_tools.rig.checks import FAILED, OK, SKIPPED

from tests.device.test_service_process import bosons  # noqa: F401  the emulated Bosons fixture

RIG = load_rig(None, [])


def _root(tmp_path, release="# R36 (release), REVISION: 4.4, GCID: 1, BOARD: generic", pin31="gpio"):
    root = tmp_path / "root"
    (root / "etc").mkdir(parents=True)
    (root / "etc" / "nv_tegra_release").write_text(release + "\n")
    t = root / "sys/kernel/debug/pinctrl/2430000.pinmux"
    t.mkdir(parents=True)
    second = ("2200000.gpio:460 function rsvd0 group soc_gpio22_pq6" if pin31 == "gpio"
              else "(MUX UNCLAIMED) (GPIO UNCLAIMED) function i2s7 group soc_gpio22_pq6")
    t.joinpath("pinmux-pins").write_text(
        "pin 132 (SOC_GPIO21_PQ5): 2200000.gpio:459 function rsvd0 group soc_gpio21_pq5\n"
        f"pin 133 (SOC_GPIO22_PQ6): {second}\n")
    return root


def test_l4t_and_pinmux_pass_on_a_good_device(tmp_path):
    root = _root(tmp_path)
    assert bringup.check_zed_l4t(RIG, root).status == OK
    c = bringup.check_pinmux(RIG, root)
    assert c.status == OK and "PQ.05" in c.detail and "PQ.06" in c.detail


def test_another_l4t_fails_naming_both(tmp_path):
    c = bringup.check_zed_l4t(RIG, _root(tmp_path, "# R35 (release), REVISION: 3.1"))
    assert c.status == FAILED and "L4T R35.3.1; the images are built for R36.4.4" in c.detail


def test_another_zed_sdk_on_the_host_fails(tmp_path):
    root = _root(tmp_path)
    hpp = root / "usr/local/zed/include/sl/Camera.hpp"
    hpp.parent.mkdir(parents=True)
    hpp.write_text("#define ZED_SDK_MAJOR_VERSION 4\n#define ZED_SDK_MINOR_VERSION 2\n#define ZED_SDK_PATCH_VERSION 5\n")
    c = bringup.check_zed_l4t(RIG, root)
    assert c.status == FAILED and "ZED SDK 4.2.5" in c.detail


def test_a_pin_muxed_to_another_function_fails(tmp_path):
    c = bringup.check_pinmux(RIG, _root(tmp_path, pin31="i2s"))
    assert c.status == FAILED and "LED pin 31 (PQ.06) is not a GPIO" in c.detail and "button" not in c.detail


def test_without_the_tables_it_is_not_measurable_here(tmp_path):
    for c in (bringup.check_zed_l4t(RIG, tmp_path), bringup.check_pinmux(RIG, tmp_path),
              bringup.check_telemetry(RIG, None), bringup.check_recorded_rate(RIG, tmp_path),
              bringup.check_trigger_edge()):
        assert c.status == SKIPPED and c.detail.startswith("not measurable here: "), c


def _frame(tmp_path, side, counter, ffc_frame):
    frame = np.zeros((514, 640), dtype="<u2")
    frame = write_into(frame, encode_line(counter, 3, ffc_frame, 640 * 2), 2)
    (tmp_path / f"{side}.raw").write_bytes(frame.tobytes())


def test_telemetry_from_frame_dumps(tmp_path):
    _frame(tmp_path, "left", 1000, 900)
    _frame(tmp_path, "right", 1001, 901)
    assert bringup.check_telemetry(RIG, tmp_path).status == OK
    _frame(tmp_path, "right", 0, 0)       # rows not where the decoder reads them: all zero
    c = bringup.check_telemetry(RIG, tmp_path)
    assert c.status == FAILED and c.detail.startswith("right: counter 0") and "layout" in c.detail
    (tmp_path / "left.raw").write_bytes(b"\0" * 100)
    assert "expected 640x514 Y16" in bringup.check_telemetry(RIG, tmp_path).detail


def _recording(out: Path, mb: float, duration: float):
    rec = out / "20261201T000000Z"
    (rec / "bag").mkdir(parents=True, exist_ok=True)
    (rec / "bag" / "bag_0.mcap").write_bytes(b"\0" * int(mb * 1e6))
    (rec / "recording.json").write_text(json.dumps({"duration_s": duration}))


def test_recorded_rate_within_and_over_budget(tmp_path):
    _recording(tmp_path, 5.0, 1.0)
    assert bringup.check_recorded_rate(RIG, tmp_path).status == OK
    _recording(tmp_path, 110.0, 1.0)
    c = bringup.check_recorded_rate(RIG, tmp_path)
    assert c.status == FAILED and "110.0 MB/s" in c.detail and "budget 100" in c.detail


def _chronyc(tmp_path, monkeypatch, leap="Normal", offset="0.000012345 seconds fast"):
    b = tmp_path / "bin"
    b.mkdir(exist_ok=True)
    (b / "chronyc").write_text(f"#!/bin/sh\ncat <<'X'\nReference ID    : C0A80001 (gw)\n"
                               f"System time     : {offset} of NTP time\nLeap status     : {leap}\nX\n")
    (b / "chronyc").chmod(0o755)
    monkeypatch.setenv("PATH", f"{b}:{os.environ['PATH']}")


@pytest.mark.parametrize("leap,offset,status", [("Normal", "0.000012345 seconds fast", OK),
                                                ("Not synchronised", "0.000012345 seconds fast", FAILED),
                                                ("Normal", "0.250000000 seconds slow", FAILED)])
def test_host_clock_from_chronyc_tracking(tmp_path, monkeypatch, leap, offset, status):
    _chronyc(tmp_path, monkeypatch, leap, offset)
    c = bringup.check_host_clock()
    assert c.status == status and f"leap status {leap}" in c.detail


def test_trigger_rate_from_the_preflight_cameras():
    assert bringup.check_trigger_rate(RIG, {"left": {"frame_rate_hz": 30.0}}).status == OK
    c = bringup.check_trigger_rate(RIG, {"left": {"frame_rate_hz": 30.0}, "right": {"frame_rate_hz": 15.0}})
    assert c.status == FAILED and "right at 15 Hz" in c.detail


# ----------------------------------------------------------------------------- the command, emulated Bosons
def bring_up(overrides, dev_dir, tmp_path, root):
    sets = [a for o in overrides("sensors.thermal.left.serial=93588", "sensors.thermal.right.serial=93589")
            for a in ("--set", o)]
    r = subprocess.run([sys.executable, "-m", "platform_tools.cli.main", "doctor", "--json", "--bring-up",
                        "--dev-dir", str(dev_dir), "--root", str(root), "--report-dir", str(tmp_path), *sets],
                       capture_output=True, text=True, timeout=90, env=os.environ)
    return r, {c["name"]: c for c in json.loads(r.stdout)["checks"]}


@pytest.mark.slow
def test_bring_up_on_a_good_fake_device_writes_both_reports(overrides, dev_dir, bosons, tmp_path, monkeypatch):  # noqa: F811
    _chronyc(tmp_path, monkeypatch)
    r, checks = bring_up(overrides, dev_dir, tmp_path, _root(tmp_path))
    assert r.returncode == 0, r.stdout + r.stderr
    for name in ("usb serial", "trigger rate", "zed sdk / l4t", "gpio pinmux", "host clock"):
        assert checks[name]["status"] == "ok", checks[name]
    assert checks["trigger edge"]["status"] == "skipped"
    doc = json.loads((tmp_path / "bringup-report.json").read_text())
    assert doc["ok"] and doc["cameras"]["left"]["serial"] == 93588
    assert "| usb serial | ok |" in (tmp_path / "bringup-report.md").read_text()


@pytest.mark.slow
def test_bring_up_sees_a_usb_serial_string_that_is_not_the_camera_serial(overrides, dev_dir, bosons, tmp_path):  # noqa: F811
    emus, _ = bosons
    link = next(emus["left"].by_id_dir.glob("*93588*"))
    link.rename(link.with_name("usb-FLIR_Boson_12345-if00"))
    r, checks = bring_up(overrides, dev_dir, tmp_path, _root(tmp_path))
    assert r.returncode == 1
    assert checks["usb serial"]["status"] == "failed"
    assert "answers SN 93588, its USB serial string is 12345" in checks["usb serial"]["detail"]


def test_stratum_16_fails_even_with_a_small_offset(tmp_path, monkeypatch):
    b = tmp_path / "bin"
    b.mkdir()
    (b / "chronyc").write_text("#!/bin/sh\ncat <<'X'\nReference ID    : 7F7F0101 ()\nStratum         : 16\n"
                               "System time     : 0.000000100 seconds fast of NTP time\nLeap status     : Normal\nX\n")
    (b / "chronyc").chmod(0o755)
    monkeypatch.setenv("PATH", f"{b}:{os.environ['PATH']}")
    c = bringup.check_host_clock()
    assert c.status == FAILED and "stratum 16 (unsynchronised)" in c.detail


@pytest.mark.slow
def test_the_regular_doctor_checks_the_pinmux_and_the_clock(overrides, dev_dir, tmp_path, monkeypatch):
    """Not only --bring-up: a pin muxed to another function and an unsynchronised clock each fail doctor."""
    _chronyc(tmp_path, monkeypatch, leap="Not synchronised")
    sets = [a for o in overrides() for a in ("--set", o)]
    r = subprocess.run([sys.executable, "-m", "firmware.cli", "doctor", "--json", "--no-boson", "--dev-dir",
                        str(dev_dir), "--root", str(_root(tmp_path, pin31="i2s")), *sets],
                       capture_output=True, text=True, timeout=90, env=os.environ)
    checks = {c["name"]: c for c in json.loads(r.stdout)["checks"]}
    assert r.returncode == 1
    assert checks["gpio pinmux"]["status"] == "failed" and "LED pin 31 (PQ.06)" in checks["gpio pinmux"]["detail"]
    assert checks["host clock"]["status"] == "failed" and "not synchronised" in checks["host clock"]["detail"]
    assert not (tmp_path / "bringup-report.json").exists()           # no report without --bring-up
