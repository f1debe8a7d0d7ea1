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
