"""Projection difference against the truth: zero for the same lens, rotation-invariant, and the
right size for a known perturbation."""
from __future__ import annotations

import mrcal
import numpy as np

from calibration.intrinsics.synthetic_corners import fisheye_truth
from calibration.lens.compare import compare, compare_models

SIZE = (640, 512)


def test_same_lens_is_zero_and_a_shifted_centre_is_not():
    lm, intr = fisheye_truth(408.3, SIZE)
    truth = mrcal.cameramodel(intrinsics=(lm, intr), imagersize=SIZE)
    c = compare_models(truth, truth)
    assert c.rms_px < 1e-6 and c.central_rms_px < 1e-6
    i2 = intr.copy()
    i2[0] *= 1.003                       # 0.3% focal error: ~1 px at the edges, ~0 at the centre
    c2 = compare_models(mrcal.cameramodel(intrinsics=(lm, i2), imagersize=SIZE), truth)
    assert 0.1 < c2.rms_px < 2.0
    assert c2.central_rms_px < c2.rms_px
    assert c2.focal_error_px[0] == np.float64(i2[0] - intr[0])


def test_a_pure_rotation_is_not_an_error():
    lm, intr = fisheye_truth(408.3, SIZE)
    r = np.array([0.002, -0.001, 0.003])
    project_rotated = lambda v: mrcal.project(mrcal.rotate_point_r(r, v), lm, intr)
    unproject = lambda q: mrcal.unproject(q, lm, intr, normalize=True)
    c = compare(project_rotated, unproject, SIZE)
    assert c.rms_px < 1e-4
    assert abs(c.rotation_deg - np.degrees(np.linalg.norm(r))) < 1e-3
    assert compare(project_rotated, unproject, SIZE, fit_rotation=False).rms_px > 0.5


def test_rotation_fitted_in_the_centre_leaves_the_centre_exact():
    """A lens wrong only far out: fitting the rotation over the central part (as cross-validation
    does) keeps the centre at zero and puts the whole error where it is."""
    lm, intr = fisheye_truth(408.3, SIZE)
    i2 = intr.copy()
    i2[8] *= 1.02                          # k3: grows as r^6, nothing at the centre
    proj = lambda v: mrcal.project(v, lm, i2)
    unproject = lambda q: mrcal.unproject(q, lm, intr, normalize=True)
    c = compare(proj, unproject, SIZE, fit_fraction=0.3)
    assert c.max_px > 0.01
    centre = c.diff_px[c.diff_px.shape[0] // 2, c.diff_px.shape[1] // 2]
    assert centre < 0.2 * c.max_px
