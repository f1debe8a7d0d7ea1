"""sync-check recovers what the simulated rig injected (truth.json): drops, jitter, offsets, FFC,
the clock step; the verdict follows the configurable limits; the plots are SVG."""
from __future__ import annotations

import json
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from platform_tools.dataset.recording import open_recording
from platform_tools.dataset.sync import Limits, analyse, find_clock_steps

CAMS = ("zed_left", "zed_right", "thermal_left", "thermal_right")


@pytest.fixture(scope="module")
def report(sim, rig):
    path, truth = sim
    return analyse(open_recording(path, rig), rig, Limits.from_rig(rig)), truth


def test_drops_per_camera_match_the_injected_ones(report):
    rep, truth = report
    for cam in CAMS:
        assert rep["streams"][cam]["drops"]["missing_frames"] == len(truth["dropped"][cam]), cam
        assert rep["streams"][cam]["frames"] == truth["frames"][cam]


def test_jitter_is_the_injected_jitter(report):
    rep, truth = report
    p = truth["params"]
    for cam in CAMS:
        injected = p["zed_jitter_ms"] if cam.startswith("zed") else p["thermal_jitter_ms"]
        assert rep["streams"][cam]["jitter_ms"] == pytest.approx(injected, rel=0.2), cam
    # the thermal pair's residual spread: two independent jitters
    pair = rep["pairs"]["thermal_left-thermal_right"]
    assert pair["residual_ms"]["std"] == pytest.approx(np.hypot(p["thermal_jitter_ms"], p["thermal_jitter_ms"]),
                                                       rel=0.25)


def test_offsets_and_drift(report):
    rep, truth = report
    off = truth["offsets_ms"]
    for cam in ("thermal_left", "thermal_right"):
        assert rep["pairs"][f"zed_left-{cam}"]["offset_ms"] == pytest.approx(off[cam] - off["zed_left"], abs=0.3)
    assert rep["pairs"]["thermal_left-thermal_right"]["offset_ms"] == pytest.approx(
        off["thermal_right"] - off["thermal_left"], abs=0.3)
    for p in rep["pairs"].values():            # one host clock: no drift beyond noise
        assert abs(p["drift_ppm"]) < 100
        assert p["residual_ms"]["max"] >= p["residual_ms"]["p99"] >= 0


def test_clock_step_found_and_taken_out(report, sim, rig):
    rep, truth = report
    step = truth["clock_step"]
    (found,) = rep["clock_steps"]
    assert found["step_ns"] == pytest.approx(step["step_ns"], abs=1e6)
    assert abs(found["at_ns"] - (step["true_ns"] + step["step_ns"])) < 1e9 / truth["params"]["imu_hz"] * 2
    # without the IMU the step is found where every camera has a gap at once
    rec = open_recording(sim[0], rig)
    del rec.streams["zed_imu"]
    (cams,) = find_clock_steps(rec, 1e9 / truth["rate_hz"])
    assert cams["found_on"] == "cameras" and cams["step_ns"] == pytest.approx(step["step_ns"], abs=3e6)


def test_ffc_periods_from_status_and_from_frozen_frames(report, sim, rig):
    rep, truth = report
    period_ns = 1e9 / truth["rate_hz"]
    for e in truth["ffc"]:   # the status node reports at frame stamps: the first frame in, the first out
        (got,) = rep["ffc"][e["camera"]]
        assert got["source"] == "status"
        assert abs(got["start_ns"] - e["start_ns"]) < period_ns and abs(got["end_ns"] - e["end_ns"]) < period_ns
    rec = open_recording(sim[0], rig)
    rec.status = {}
    from platform_tools.dataset.sync import ffc_periods
    for e in truth["ffc"]:
        (got,) = ffc_periods(rec, e["camera"], 1e9 / truth["rate_hz"])
        assert got["source"] == "frozen frames"
        assert abs(got["start_ns"] - e["start_ns"]) < 2 * 1e9 / truth["rate_hz"]
        assert abs(got["end_ns"] - e["end_ns"]) < 2 * 1e9 / truth["rate_hz"]


@pytest.mark.slow
def test_command_json_and_plots(platform_tools, sim, tmp_path):
    # the simulation drops 2 % of frames at random: about 3 % here, above the default 2 % limit
    r = platform_tools("sync-check", str(sim[0]), "--json", "--plots", str(tmp_path / "plots"),
                       "--set", "processing.sync_limits.max_drop_percent=6")
    assert r.returncode == 0, r.stderr
    rep = json.loads(r.stdout)
    assert rep["verdict"] == "pass" and all(c["ok"] for c in rep["checks"])
    svgs = sorted((tmp_path / "plots").glob("*.svg"))
    assert {p.name for p in svgs} >= {"intervals_thermal_left.svg", "residuals_zed_left-thermal_left.svg"}
    for p in svgs:
        root = ET.parse(p).getroot()
        assert root.tag.endswith("svg")
    ffc_plot = (tmp_path / "plots" / "residuals_zed_left-thermal_left.svg").read_text()
    assert "FFC thermal_left" in ffc_plot


@pytest.mark.slow
def test_limits_are_configurable_and_fail_with_exit_1(platform_tools, sim):
    r = platform_tools("sync-check", str(sim[0]), "--set", "processing.sync_limits.max_pair_jitter_p99_ms=0.05",
                       "--set", "processing.sync_limits.max_drop_percent=6")
    assert r.returncode == 1, r.stderr
    fails = [line for line in r.stdout.splitlines() if line.startswith("FAIL ")]
    assert len(fails) == 3 and all("jitter p99" in line for line in fails)


@pytest.mark.slow
def test_a_drifting_thermal_clock_is_measured_and_fails(rig, tmp_path):
    from platform_tools.sim.timeline import SimParams
    from platform_tools.sim.writer import simulate
    simulate(rig, tmp_path / "rec", SimParams(8.0, seed=2, drop_probability=0.0, thermal_drift_ppm=400.0),
             scale=0.05)
    rep = analyse(open_recording(tmp_path / "rec", rig), rig, Limits.from_rig(rig))
    for cam in ("thermal_left", "thermal_right"):
        p = rep["pairs"][f"zed_left-{cam}"]
        assert p["drift_ppm"] == pytest.approx(400.0, abs=3 * p["drift_stderr_ppm"] + 10)
    assert abs(rep["pairs"]["thermal_left-thermal_right"]["drift_ppm"]) < 100
    assert rep["verdict"] == "fail"
    assert {c["check"] for c in rep["checks"] if not c["ok"]} == {"zed_left-thermal_left drift",
                                                                 "zed_left-thermal_right drift"}
