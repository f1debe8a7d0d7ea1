"""The verdict names what is wrong; the report is self-contained."""
from __future__ import annotations

import re

import numpy as np
import pytest

from calibration.intrinsics import mrcal_solver
from calibration.intrinsics.outputs import build
from calibration.intrinsics.synthetic_corners import fisheye_truth, simulate
from calibration.report.verdict import judge

SIZE = (640, 512)
REGIONS = ["top-left corner", "top edge", "top-right corner", "left edge", "centre", "right edge",
           "bottom-left corner", "bottom edge", "bottom-right corner"]


def test_verdict_names_the_empty_corner():
    counts = {r: 100 for r in REGIONS}
    counts["top-left corner"] = 0
    v = judge(region_counts=counts, rms_px=0.1, n_images=30, n_rejected_images=0,
              uncertainty_central_px=0.05, uncertainty_max_px=0.2)
    assert not v.trustworthy and "the top-left corner has no data" in v.headline
    ok = judge(region_counts={r: 100 for r in REGIONS}, rms_px=0.1, n_images=30, n_rejected_images=1,
               uncertainty_central_px=0.05, uncertainty_max_px=0.2)
    assert ok.trustworthy and "rejected" in ok.headline
    unc = judge(region_counts={r: 100 for r in REGIONS}, rms_px=0.1, n_images=30, n_rejected_images=0,
                uncertainty_central_px=0.4, uncertainty_max_px=3.0)
    assert not unc.trustworthy and "uncertainty" in unc.headline


@pytest.mark.slow
def test_centre_only_boards_solve_but_are_not_trusted():
    lm, intr = fisheye_truth(408.3, SIZE)
    s = simulate(lm, intr, SIZE, n=10, noise_px=0.05, seed=1, region="centre", distance_m=(1.2, 1.6))
    sol = mrcal_solver.solve(s.observations, lensmodel=None, focal_px=408.3)
    out = build(sol, camera_name="thermal", rig_hash="0" * 40, corners_vnl="# filename x y level\n")
    assert not out.verdict.trustworthy
    assert any("corner has no data" in r or "uncertainty" in r for r in out.verdict.reasons)
    page = out.files["report.html"]
    assert "not trustworthy" in page and page.count("<svg") >= 5
    assert not re.search(r'(src|href)\s*=\s*"(https?:)?//', page)     # nothing fetched
    assert out.summary["uncertainty"]["max_px"] > out.summary["uncertainty"]["central_max_px"]


def _without_image_corners(obs, radius_px: float):
    """The same observations with every corner within radius_px of an image corner removed."""
    o = obs.subset(np.arange(obs.n))
    w, h = o.imagersize
    for cx, cy in ((0, 0), (w - 1, 0), (0, h - 1), (w - 1, h - 1)):
        near = np.hypot(o.corners[..., 0] - cx, o.corners[..., 1] - cy) < radius_px
        o.corners[near] = np.nan
        o.weights[near] = 0.0
    return o


@pytest.fixture(scope="module")
def covered():
    lm, intr = fisheye_truth(408.3, SIZE)
    return simulate(lm, intr, SIZE, n=40, noise_px=0.05, seed=11, tilt_deg=35.0)


def test_cross_validation_rejects_uncovered_corners_and_accepts_a_covered_set(covered):
    import mrcal
    sol = mrcal_solver.solve(covered.observations, lensmodel=None, focal_px=408.3)
    good = build(sol, camera_name="thermal", rig_hash="0" * 40, corners_vnl="# filename x y level\n")
    assert good.verdict.trustworthy, good.verdict.headline
    assert good.summary["validity"]["trusted_share"] > 0.99
    assert good.summary["cross_validation"]["max_px"] < 0.5

    holes = _without_image_corners(covered.observations, 150.0)
    sol2 = mrcal_solver.solve(holes, lensmodel=None, focal_px=408.3)
    bad = build(sol2, camera_name="thermal", rig_hash="0" * 40, corners_vnl="# filename x y level\n")
    assert not bad.verdict.trustworthy
    said = " ".join(bad.verdict.reasons)
    for corner in ("top-left", "top-right", "bottom-left", "bottom-right"):
        assert f"the {corner} corner has no data" in said, said
    assert "halves" in said
    # the valid-intrinsics region is in the .cameramodel: the middle is in it, the corners are not
    import io
    m = mrcal.cameramodel(io.StringIO(bad.files["thermal.cameramodel"]))
    region = m.valid_intrinsics_region()
    assert region is not None and len(region) >= 4
    assert mrcal.is_within_valid_intrinsics_region(np.array([320.0, 256.0]), m)
    assert not mrcal.is_within_valid_intrinsics_region(np.array([5.0, 5.0]), m)
    assert 0.5 < bad.summary["validity"]["trusted_share"] < 0.99
    page = bad.files["report.html"]
    assert "cross-validation" in page.lower() and "valid-intrinsics region" in page


def test_region_sentence_names_the_disagreement():
    from calibration.report.validity import RegionTrust
    s = RegionTrust("top-left corner", 0.3, 1.0, 3.14, float("nan")).sentence()
    assert s == "the top-left corner has no data: the halves disagree by 3.1 px there"
