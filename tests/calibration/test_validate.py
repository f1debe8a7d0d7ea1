"""Projection difference against the truth: zero for the same lens, rotation-invariant, and the
right size for a known perturbation."""
from __future__ import annotations

import mrcal
import numpy as np
import pytest

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


# --- calibrate validate against a Kannala-Brandt truth (truth_fisheye.yaml, read by cv2 alone)

def _kb_set(tmp_path):
    """A Kannala-Brandt truth set's files, and .cameramodels of the nearest OPENCV8 to it (fitted from
    the truth lens' own closed form) and of that one with a 0.3 % focal error."""
    import io
    from calibration.lens.fit import fit_lensmodel
    from calibration.synth.truth_families import truth_lens
    from calibration.synth.truth_files import write_truth_files
    lens = truth_lens("kannala-brandt", SIZE)
    write_truth_files(tmp_path, lens, "test")
    fit = fit_lensmodel(lens.unproject, SIZE, "LENSMODEL_OPENCV8",
                        np.array([lens.fx, lens.fy, lens.cx, lens.cy]), n_width=64)
    paths = []
    for name, scale in (("near.cameramodel", 1.0), ("long.cameramodel", 1.003)):
        i = fit.intrinsics.copy()
        i[:2] *= scale
        buf = io.StringIO()
        mrcal.cameramodel(intrinsics=("LENSMODEL_OPENCV8", i), imagersize=SIZE).write(buf)
        (tmp_path / name).write_text(buf.getvalue())
        paths.append(tmp_path / name)
    return lens, fit, paths


@pytest.mark.slow
def test_validate_reads_a_kannala_brandt_truth_through_cv2_fisheye(tmp_path, capsys):
    import json
    from calibration.cli import main
    lens, fit, (near, long) = _kb_set(tmp_path)
    assert not (tmp_path / "truth.cameramodel").exists()
    assert main(["validate", str(near), "--truth", str(tmp_path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["truth"].endswith("truth_fisheye.yaml") and out["truth_lensmodel"].startswith("KANNALA_BRANDT")
    # the difference is the OPENCV8 fit's own error over the image, measured by an independent path
    assert out["rms_px"] < max(2 * fit.rms_px, 0.01) and out["max_px"] < max(2 * fit.max_px, 0.05)
    assert abs(out["focal_error_px"][0] - (fit.intrinsics[0] - lens.fx)) < 1e-6      # the YAML keeps ~9 digits
    assert main(["validate", str(long), "--truth", str(tmp_path / "truth_fisheye.yaml"), "--json"]) == 1
    bad = json.loads(capsys.readouterr().out)
    assert bad["rms_px"] > 0.1 and bad["within_targets"] is False


@pytest.mark.slow
def test_validate_refuses_a_truth_folder_without_truth_and_a_broken_fisheye_yaml(tmp_path, capsys):
    from calibration.cli import main
    lens, fit, (near, _) = _kb_set(tmp_path)
    empty = tmp_path / "empty"
    empty.mkdir()
    assert main(["validate", str(near), "--truth", str(empty)]) == 2
    assert "no truth.cameramodel or truth_fisheye.yaml" in capsys.readouterr().err
    broken = tmp_path / "broken.yaml"
    broken.write_text("%YAML:1.0\n---\ncamera_matrix: 3\n")
    assert main(["validate", str(near), "--truth", str(broken)]) == 2
    err = capsys.readouterr().err
    assert "broken.yaml" in err and "distortion_coefficients" in err
