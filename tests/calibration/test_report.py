"""The verdict names what is wrong and grades it (trusted / trusted-within-region / not-trusted);
the report is self-contained."""
from __future__ import annotations

import io
import math
import re

import numpy as np
import pytest

from calibration.intrinsics import mrcal_solver
from calibration.lens.fit import imager_grid
from calibration.thermal.outputs import build
from calibration.intrinsics.synthetic_corners import fisheye_truth, simulate
from calibration.report import verdict as vd
from calibration.report.validity import validity as trust_map
from calibration.report.verdict import judge
from calibration.lens.compare import central_mask, compare

SIZE = (640, 512)
REGIONS = ["top-left corner", "top edge", "top-right corner", "left edge", "centre", "right edge",
           "bottom-left corner", "bottom edge", "bottom-right corner"]


def test_verdict_names_the_empty_corner():
    counts = {r: 100 for r in REGIONS}
    counts["top-left corner"] = 0
    v = judge(region_counts=counts, rms_px=0.1, n_images=30, n_rejected_images=0,
              uncertainty_central_px=0.05, uncertainty_max_px=0.2)
    # without a trust map there is no region to be trusted within: whole image or nothing
    assert v.grade == "not-trusted" and not v.trustworthy and "the top-left corner has no data" in v.headline
    ok = judge(region_counts={r: 100 for r in REGIONS}, rms_px=0.1, n_images=30, n_rejected_images=1,
               uncertainty_central_px=0.05, uncertainty_max_px=0.2)
    assert ok.grade == "trusted" and ok.trustworthy and "rejected" in ok.headline
    unc = judge(region_counts={r: 100 for r in REGIONS}, rms_px=0.1, n_images=30, n_rejected_images=0,
                uncertainty_central_px=0.4, uncertainty_max_px=3.0)
    assert unc.grade == "not-trusted" and not unc.trustworthy and "uncertainty" in unc.headline


# A trust map built by validity() itself, on the 32 x 26 grid calibrate thermal uses: corners seen at
# every grid point (or all but those near chosen spots), the halves agreeing (0.05 px) except at
# chosen points, where they disagree (2 px) and the point is untrusted.
GRID = imager_grid(SIZE, 32)
CENTRAL = central_mask(GRID, SIZE).ravel()
_FROM_TOP_LEFT = np.argsort(np.hypot(*GRID.reshape(-1, 2).T), kind="stable")
OUTER = [i for i in _FROM_TOP_LEFT if not CENTRAL[i]]      # outside the central 80%, top-left first
INNER = [i for i in _FROM_TOP_LEFT if CENTRAL[i]]
ALL = {r: 100 for r in REGIONS}


def _map(disagree=(), *, no_corners_within: float = 0.0, halves: float = 0.05):
    d = np.full(GRID.shape[:2], halves)
    d.flat[list(disagree)] = 2.0
    pts = GRID.reshape(-1, 2)
    pts = pts[np.hypot(pts[:, 0], pts[:, 1]) >= no_corners_within]
    return trust_map(GRID, pts, SIZE, halves_diff_px=d, uncertainty_px=np.full(GRID.shape[:2], 0.1))


def _judge(val, **kw):
    args = dict(region_counts=ALL, rms_px=0.1, n_images=30, n_rejected_images=0, uncertainty_central_px=0.05,
                uncertainty_max_px=0.3, validity=val, cross_validated=True)
    return judge(**dict(args, **kw))


def test_grades_and_their_headlines():
    whole = _judge(_map())
    assert whole.grade == "trusted" and whole.trustworthy and whole.trusted_share == 1.0
    assert whole.headline == "trusted over the whole image" and not whole.reasons

    # no board near the top-left image corner: trusted within the valid region, that corner named
    val = _map(no_corners_within=120.0)
    assert val.central_trusted_share == 1.0 and vd.MIN_TRUSTED_SHARE <= val.trusted_share < 1 - vd.MAX_UNTRUSTED_SHARE
    v = _judge(val)
    assert v.grade == "trusted-within-region" and v.trustworthy and not v.reasons
    assert v.headline.startswith(f"trusted within its valid region ({100 * val.trusted_share:.0f}% of the image): "
                                 f"the top-left corner has no data")
    assert v.headline.endswith("take images with the board there to extend it")
    assert val.regions[0].name == "top-left corner" and val.regions[0].sentence() in v.warnings
    d = v.to_dict()
    assert d["grade"] == "trusted-within-region" and d["trustworthy"] is True
    assert d["trusted_share"] == pytest.approx(val.trusted_share) and d["headline"] == v.headline

    # every other reason still disqualifies; the region is still named among the reasons
    for kw, said in [(dict(rms_px=0.8), "RMS reprojection error"),
                     (dict(n_images=20, n_rejected_images=10), "10 of 30 images rejected"),
                     (dict(uncertainty_central_px=0.3), "central 80%"),
                     (dict(cross_validated=False), "too few images")]:
        bad = _judge(val, **kw)
        assert bad.grade == "not-trusted" and not bad.trustworthy, kw
        assert bad.headline.startswith("not trusted: ") and said in bad.headline, kw
        assert val.regions[0].sentence() in bad.reasons, kw
        assert bad.to_dict()["trustworthy"] is False and bad.to_dict()["grade"] == "not-trusted"


def test_sparse_ninth_limits_to_the_region_only_with_a_trust_map():
    counts = dict(ALL, **{"top-left corner": 12})
    v = _judge(_map(), region_counts=counts)
    assert v.grade == "trusted-within-region"
    assert "little data in the top-left corner (12 corners)" in v.headline
    without_map = _judge(None, region_counts=counts)
    assert without_map.grade == "not-trusted" and without_map.trusted_share is None


def test_identical_halves_are_a_failed_cross_validation():
    """Halves that agree to 1e-8 px did not move from the full solve: nothing was cross-validated."""
    v = _judge(_map(halves=1e-8))
    assert v.grade == "not-trusted" and "cross-validation failed" in v.headline
    assert _judge(_map(halves=1e-3)).grade == "trusted"


def test_thresholds_at_their_boundaries():
    n, n_central = GRID.shape[0] * GRID.shape[1], int(CENTRAL.sum())
    # at most MAX_UNTRUSTED_SHARE of the image untrusted: still trusted over the whole image, with a warning
    k = math.floor(vd.MAX_UNTRUSTED_SHARE * n)
    at, over = _judge(_map(OUTER[:k])), _judge(_map(OUTER[:k + 1]))
    assert at.grade == "trusted" and "top-left corner" in " ".join(at.warnings)
    assert over.grade == "trusted-within-region"

    # the whole image's trusted share around MIN_TRUSTED_SHARE (all the untrusted points outside the centre)
    k = math.floor((1 - vd.MIN_TRUSTED_SHARE) * n)
    just_in, just_out = _map(OUTER[:k]), _map(OUTER[:k + 1])
    assert just_in.trusted_share >= vd.MIN_TRUSTED_SHARE > just_out.trusted_share
    assert just_in.central_trusted_share == just_out.central_trusted_share == 1.0
    assert _judge(just_in).grade == "trusted-within-region"
    out = _judge(just_out)
    assert out.grade == "not-trusted" and "at least 80% needed" in out.headline

    # the central 80% around MIN_CENTRAL_TRUSTED_SHARE, with the rest of the image as above
    k = math.floor((1 - vd.MIN_CENTRAL_TRUSTED_SHARE) * n_central)
    ok, holed = _map(OUTER[:20] + INNER[:k]), _map(OUTER[:20] + INNER[:k + 1])
    assert ok.central_trusted_share >= vd.MIN_CENTRAL_TRUSTED_SHARE > holed.central_trusted_share
    assert _judge(ok).grade == "trusted-within-region"
    h = _judge(holed)
    assert h.grade == "not-trusted" and "of the central 80% of the image is trusted" in h.headline
    # a hole in the centre is not "trusted" either, however small the share of the whole image
    small = _map(INNER[:k + 1])
    assert 1 - small.trusted_share <= vd.MAX_UNTRUSTED_SHARE and _judge(small).grade == "not-trusted"


@pytest.mark.slow
def test_centre_only_boards_solve_but_are_not_trusted():
    lm, intr = fisheye_truth(408.3, SIZE)
    s = simulate(lm, intr, SIZE, n=10, noise_px=0.05, seed=1, region="centre", distance_m=(1.2, 1.6))
    sol = mrcal_solver.solve(s.observations, lensmodel=None, focal_px=408.3)
    out = build(sol, camera_name="thermal", rig_hash="0" * 40, corners_vnl="# filename x y level\n")
    assert not out.verdict.trustworthy and out.verdict.grade == "not-trusted"
    assert any("corner has no data" in r or "uncertainty" in r for r in out.verdict.reasons)
    page = out.files["report.html"]
    assert 'class="verdict bad"' in page and "not trusted" in page and page.count("<svg") >= 5
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
    return simulate(lm, intr, SIZE, n=40, noise_px=0.05, seed=13, tilt_deg=35.0)   # see test_cross_validation_grades_uncovered_corners


@pytest.mark.slow
def test_cross_validation_grades_uncovered_corners(covered):
    """A covered set is trusted over the whole image. Without corners near the four image corners
    the model may be far off there, but where the verdict trusts it, it is right: trusted within its
    region, and accurate inside it. With the holes reaching into the central 80%: not trusted.

    The premise, an OPENCV8 solve with no pole out to the image corners on the covered set, is fragile:
    with seed 11 the pole sits at 53.6 deg (corners at 57.9) with OpenBLAS's AVX2/AVX-512 kernels and
    out of the image with its Sandybridge kernel; seeds 12 and 17 have it inside on all three. Seed 13
    holds it on all three (OPENBLAS_CORETYPE=Haswell, SkylakeX, Sandybridge). The product's default
    does not rest on it: calibration/thermal/pipeline.py sets such an OPENCV8 aside for Kannala-Brandt."""
    import mrcal
    lm, intr = fisheye_truth(408.3, SIZE)

    def truth_error(out):
        """Projection difference against the true lens on the validity grid (rotation fitted over the
        central 80%, as for a model used within its region) and the valid-intrinsics region."""
        m = mrcal.cameramodel(io.StringIO(out.files["thermal.cameramodel"]))
        lm2, i2 = m.intrinsics()
        c = compare(lambda v: mrcal.project(np.ascontiguousarray(v), lm2, i2),
                    lambda q: mrcal.unproject(np.ascontiguousarray(q), lm, intr, normalize=True), SIZE,
                    grid_width=32, fit_fraction=0.8)
        inside = np.array([mrcal.is_within_valid_intrinsics_region(q, m) for q in c.grid.reshape(-1, 2)])
        return c, m, inside.reshape(c.grid.shape[:2])

    sol = mrcal_solver.solve(covered.observations, lensmodel=None, focal_px=408.3)
    good = build(sol, camera_name="thermal", rig_hash="0" * 40, corners_vnl="# filename x y level\n")
    assert good.verdict.grade == "trusted" and good.verdict.trustworthy, good.verdict.headline
    assert good.summary["validity"]["trusted_share"] > 0.99
    # the halves' largest disagreement (at an image corner): 0.25 px on this set, the same in every run
    # since the OPENCV8 seed is a linear fit (calibration/lens/radial.py); an iterative seed fit varied it
    # 0.33-0.55 px with what ran before in the process
    assert good.summary["cross_validation"]["max_px"] < 0.35
    assert 'class="verdict ok"' in good.files["report.html"]

    holes = _without_image_corners(covered.observations, 130.0)
    sol2 = mrcal_solver.solve(holes, lensmodel=None, focal_px=408.3)
    part = build(sol2, camera_name="thermal", rig_hash="0" * 40, corners_vnl="# filename x y level\n")
    v = part.verdict
    assert v.grade == "trusted-within-region" and v.trustworthy and not v.reasons, v.headline
    assert part.summary["verdict"]["grade"] == "trusted-within-region"
    said = " ".join(v.warnings)
    for corner in ("top-left", "top-right", "bottom-left", "bottom-right"):
        assert f"the {corner} corner has no data" in said, said
    assert "halves" in said and "take images with the board there" in v.headline
    assert 0.8 <= part.summary["validity"]["trusted_share"] < 0.99
    assert part.summary["validity"]["central_trusted_share"] >= 0.99
    # the valid-intrinsics region is in the .cameramodel: the middle is in it, the corners are not
    c, m, inside = truth_error(part)
    region = m.valid_intrinsics_region()
    assert region is not None and len(region) >= 4
    assert mrcal.is_within_valid_intrinsics_region(np.array([320.0, 256.0]), m)
    assert not mrcal.is_within_valid_intrinsics_region(np.array([5.0, 5.0]), m)
    # safety: where it is trusted it is right; off by more than that somewhere, it is not "trusted"
    assert inside.mean() > 0.8 and c.diff_px[inside].max() < 0.3, c.diff_px[inside].max()
    if c.max_px > 0.3:
        assert v.grade != "trusted"
    page = part.files["report.html"]
    assert "cross-validation" in page.lower() and "valid-intrinsics region" in page
    assert 'class="verdict partial"' in page and 'data-grade="trusted-within-region"' in page

    deep = _without_image_corners(covered.observations, 200.0)
    sol3 = mrcal_solver.solve(deep, lensmodel=None, focal_px=408.3)
    bad = build(sol3, camera_name="thermal", rig_hash="0" * 40, corners_vnl="# filename x y level\n")
    assert bad.verdict.grade == "not-trusted" and not bad.verdict.trustworthy
    said = " ".join(bad.verdict.reasons)
    for corner in ("top-left", "top-right", "bottom-left", "bottom-right"):
        assert f"the {corner} corner has no data" in said, said
    assert "of the central 80% of the image is trusted" in said
    assert 'class="verdict bad"' in bad.files["report.html"]


def test_region_sentence_names_the_disagreement():
    from calibration.report.validity import RegionTrust
    s = RegionTrust("top-left corner", 0.3, 1.0, 3.14, float("nan")).sentence()
    assert s == "the top-left corner has no data: the halves disagree by 3.1 px there"
