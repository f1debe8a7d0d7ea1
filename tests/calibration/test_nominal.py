"""Nominal camera models: written by `calibrate nominal`, read back by mrcal, posed as the rig says."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from platform_tools.rig import load_rig

mrcal = pytest.importorskip("mrcal")


@pytest.mark.slow
def test_nominal_models_project_rig_points(tmp_path: Path, calibrate):
    rig = load_rig()
    out = tmp_path / "nominal"
    r = calibrate("nominal", "--out", str(out), "--json")
    assert r.returncode == 0, r.stderr
    listed = json.loads(r.stdout)
    assert {Path(w["file"]).name for w in listed} == {
        "zed_x_left.cameramodel", "zed_x_right.cameramodel", "thermal_left.cameramodel", "thermal_right.cameramodel"}

    m = mrcal.cameramodel(str(out / "thermal_left.cameramodel"))
    spec = rig.camera_model(rig.desc.sensors.thermal.camera_model)
    assert tuple(m.imagersize()) == (spec.width_px, spec.height_px)
    assert m.intrinsics()[1][0] == pytest.approx(rig.focal_px(spec))
    # a point 2 m straight ahead of the left thermal camera lands on its principal point
    T = rig.frame("thermal_left_optical")
    p_rig_m = T.apply([0, 0, 2000.0]) / 1000.0
    p_cam = mrcal.transform_point_rt(m.extrinsics_rt_fromref(), p_rig_m)
    np.testing.assert_allclose(mrcal.project(p_cam, *m.intrinsics()), m.intrinsics()[1][2:4], atol=1e-6)
    # a point 2 m ahead and 0.5 m to the rig's left shows up left of centre (x smaller) in the image
    p_left = (T.apply([0, 0, 2000.0]) + [0, 500.0, 0]) / 1000.0
    q = mrcal.project(mrcal.transform_point_rt(m.extrinsics_rt_fromref(), p_left), *m.intrinsics())
    assert q[0] < m.intrinsics()[1][2]


@pytest.mark.slow
def test_nominal_follows_overrides(tmp_path: Path, calibrate):
    out = tmp_path / "nominal"
    r = calibrate("nominal", "--out", str(out), "--set", "sensors.thermal.baseline_mm=200")
    assert r.returncode == 0, r.stderr
    left = mrcal.cameramodel(str(out / "thermal_left.cameramodel"))
    right = mrcal.cameramodel(str(out / "thermal_right.cameramodel"))
    # camera centres in the rig frame are 200 mm apart
    c_left = mrcal.invert_rt(left.extrinsics_rt_fromref())[3:]
    c_right = mrcal.invert_rt(right.extrinsics_rt_fromref())[3:]
    assert np.linalg.norm(c_left - c_right) == pytest.approx(0.200)
