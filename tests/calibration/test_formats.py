"""The exported files project like the solved lens, read back by the tools that use them."""
from __future__ import annotations

import pytest

import cv2
import mrcal
import numpy as np
import yaml

from platform_tools.rig.cameras import camera_model

from calibration import formats
from calibration.formats.conversions import projector
from calibration.lens import kannala_brandt as kb
from calibration.intrinsics.synthetic_corners import fisheye_truth

SIZE = (640, 512)


def rays(n=200, seed=0):
    q = np.random.default_rng(seed).uniform([0, 0], [639, 511], (n, 2))
    return q


def test_opencv8_is_exact_in_opencv_yaml_and_projects_like_mrcal(tmp_path):
    lm, intr = fisheye_truth(408.3, SIZE)
    lens = camera_model(lm, intr, SIZE)
    rep = formats.exact_or_nearest(lens)
    assert rep.family == "rational_polynomial" and rep.exact
    p = tmp_path / "c.yaml"
    p.write_text(formats.opencv_yaml(rep, SIZE, camera_name="thermal", rms_px=0.1))
    fs = cv2.FileStorage(str(p), cv2.FILE_STORAGE_READ)
    K, D = fs.getNode("camera_matrix").mat(), fs.getNode("distortion_coefficients").mat().ravel()
    assert fs.getNode("distortion_model").string() == "rational_polynomial" and len(D) == 8
    v = mrcal.unproject(rays(), lm, intr)
    q_cv, _ = cv2.projectPoints(v, np.zeros(3), np.zeros(3), K, D)
    np.testing.assert_allclose(q_cv[:, 0], mrcal.project(v, lm, intr), atol=1e-6)


def test_a_95_deg_lens_goes_to_ros_as_equidistant_and_image_geometry_default_inversion_is_why(tmp_path):
    """ROS image_geometry inverts plumb_bob / rational_polynomial with cv::undistortPoints' default 5
    iterations: on the healthy 95 deg synthetic lens that is px off in the corners, so the ROS file is
    equidistant, fitted, with its error in the first line, and cv2.fisheye reads it back exactly."""
    lm, intr = fisheye_truth(408.3, SIZE)
    lens = camera_model(lm, intr, SIZE)
    K = np.array([[intr[0], 0, intr[2]], [0, intr[1], intr[3]], [0, 0, 1]])
    corner = np.array([[[0.0, 0.0]]])
    x = cv2.undistortPoints(corner, K, np.array(intr[4:]))[0, 0]
    back = mrcal.project(np.array([x[0], x[1], 1.0]), lm, intr)
    assert np.linalg.norm(back - corner[0, 0]) > 1.0          # the default inversion, 1+ px off
    rep = formats.nearest_for_ros(lens)
    assert rep.family == "equidistant" and not rep.exact and rep.fit.max_px < 0.01
    text = formats.ros_camera_info(rep, SIZE, camera_name="thermal")
    doc = yaml.safe_load(text)
    assert doc["distortion_model"] == "equidistant" and len(doc["distortion_coefficients"]["data"]) == 4
    assert "fitted" in text.splitlines()[0]
    K2 = np.array(doc["camera_matrix"]["data"]).reshape(3, 3)
    D2 = np.array(doc["distortion_coefficients"]["data"])
    v = mrcal.unproject(rays(), lm, intr)
    q, _ = cv2.fisheye.projectPoints(v[None], np.zeros(3), np.zeros(3), K2, D2)
    assert np.abs(q[0] - mrcal.project(v, lm, intr)).max() < 0.01


def test_kannala_brandt_exports_exactly_as_fisheye_and_equidistant(tmp_path):
    p = np.array([405.0, 404.0, 321.0, 255.0, 0.02, -0.004, 0.001, -0.0002])
    lens = kb.KannalaBrandt(p, SIZE)
    rep = formats.nearest_for_ros(lens)
    assert rep.family == "equidistant" and rep.exact
    f = tmp_path / "c.yaml"
    f.write_text(formats.opencv_yaml(rep, SIZE, camera_name="t"))
    fs = cv2.FileStorage(str(f), cv2.FILE_STORAGE_READ)
    assert fs.getNode("distortion_model").string() == "fisheye"
    K, D = fs.getNode("camera_matrix").mat(), fs.getNode("distortion_coefficients").mat().ravel()
    v = kb.unproject(rays(), p)
    q, _ = cv2.fisheye.projectPoints(v[None], np.zeros(3), np.zeros(3), K, D)
    np.testing.assert_allclose(q[0], kb.project(v, p), atol=1e-6)
    kal = yaml.safe_load(formats.kalibr_camchain(formats.nearest_kalibr(lens), SIZE, rostopic="/t/image_raw"))
    cam = kal["cam0"]
    assert cam["camera_model"] == "pinhole" and cam["distortion_model"] == "equidistant"
    np.testing.assert_allclose(cam["intrinsics"] + cam["distortion_coeffs"], p)


@pytest.mark.slow
def test_splined_has_no_ros_equivalent_so_the_nearest_fit_is_reported():
    lm, intr = fisheye_truth(408.3, SIZE)
    sp = "LENSMODEL_SPLINED_STEREOGRAPHIC_order=3_Nx=12_Ny=10_fov_x_deg=100"
    from calibration.lens.fit import fit_lensmodel, mrcal_unprojector
    fit = fit_lensmodel(mrcal_unprojector(lm, intr), SIZE, sp, np.r_[intr[:4]], fix_core=False)
    lens = camera_model(sp, fit.intrinsics, SIZE)
    rep = formats.nearest_for_ros(lens)
    assert not rep.exact and rep.fit.rms_px < 0.5
    text = formats.ros_camera_info(rep, SIZE, camera_name="thermal")
    assert "no" in text.splitlines()[0] and "equivalent" in text.splitlines()[0]
    # the fit really is close: project through the representation and compare with the splined lens
    v = mrcal.unproject(rays(), sp, fit.intrinsics)
    p2 = np.r_[rep.K[0, 0], rep.K[1, 1], rep.K[0, 2], rep.K[1, 2], rep.D]
    lens2 = camera_model("LENSMODEL_OPENCV8", p2, SIZE) if rep.family == "rational_polynomial" else \
        kb.KannalaBrandt(p2, SIZE)
    d = np.linalg.norm(projector(lens2)(v) - mrcal.project(v, sp, fit.intrinsics), axis=-1)
    assert np.sqrt(np.mean(d ** 2)) < 2 * rep.fit.rms_px + 0.05
