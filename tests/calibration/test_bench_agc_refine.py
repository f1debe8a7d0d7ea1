"""bench/bench_agc_refine.py's two judgements: a corner's lattice spacing is the detector's (corner_spacing: the
nearest labelled neighbour), and a board is "right" only when it is complete with every corner within 1 px of the
truth, in either ordering."""
from __future__ import annotations

import numpy as np

from calibration.detect.detector import corner_spacing
from tests.conftest import bench_module


def _bench():
    return bench_module("bench_agc_refine")


def test_the_spacing_is_the_detectors_nearest_neighbour():
    bench = _bench()
    W, H = bench.BOARD
    rng = np.random.default_rng(0)
    j, i = np.mgrid[0:H, 0:W]
    ij = np.stack([i.ravel(), j.ravel()], 1)
    # a foreshortened lattice: steps grow along i and shrink along j, so the nearest neighbour changes axis
    xy = np.stack([20 * ij[:, 0] * (1 + 0.05 * ij[:, 0]), 25 * ij[:, 1] * (1 - 0.06 * ij[:, 1])], 1)
    xy = xy + rng.normal(0, 0.5, xy.shape)
    got = bench.lattice_spacing(xy, W, H)
    assert np.allclose(got, corner_spacing(xy, ij))
    assert got.min() < 15 and got.max() > 20          # both axes are the nearest somewhere


def test_a_board_is_right_only_complete_and_within_1_px():
    bench = _bench()
    W, H = bench.BOARD
    true = np.random.default_rng(1).uniform(0, 600, (W * H, 2))
    off = true.copy()
    off[7] += [0.99, 0.0]
    assert bench.right(off, true) and bench.right(off[::-1], true)      # either ordering
    off[7] = true[7] + [0.0, 1.01]
    assert not bench.right(off, true)
    gap = true.copy()
    gap[3] = np.nan
    assert not bench.right(gap, true) and not bench.right(None, true)


def test_the_peak_of_a_rendered_x_corner_is_the_corner():
    """The bench's peak@truth estimator on an ideal blurred X-corner at sub-pixel places: found within 0.02 px from a
    start 1.4 px away; a start by the image's edge or not finite gives NaN."""
    from scipy.special import erf
    bench = _bench()
    yy, xx = np.mgrid[0:41, 0:41].astype(float)
    for cx, cy in ((20.3, 19.6), (20.5, 20.25), (20.8, 19.1)):
        img = (100.0 + 80.0 * erf((xx - cx) / 1.5) * erf((yy - cy) / 1.5)).astype(np.float32)
        got = bench.response_peak(img, np.array([[cx + 1.2, cy - 0.8], [1.0, 1.0], [np.nan, 3.0]]))
        assert np.allclose(got[0], [cx, cy], atol=0.02)
        assert np.isnan(got[1:]).all()
