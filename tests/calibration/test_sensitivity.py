"""calibration.intrinsics.sensitivity: the first-order effect of corner errors on a solved lens,
checked against mrcal re-solving the perturbed problem."""
import mrcal
import numpy as np
import pytest

from calibration.intrinsics.sensitivity import parameter_shift, problem_at_truth
from calibration.intrinsics.synthetic_corners import simulate

SIZE = (640, 512)


@pytest.fixture(scope="module")
def truth_problem():
    # the synthetic images' lens (an OPENCV8 fitted linearly to a fisheye profile), not
    # fisheye_truth's least-squares fit, whose rational terms sit anywhere along a valley of
    # near-equal lenses, where a first-order answer means little
    from calibration.synth.dataset import default_lens
    lens = default_lens()
    lm, intr = lens.intrinsics()
    s = simulate(lm, intr, SIZE, n=16, noise_px=0.0, seed=5)
    oi = problem_at_truth(lm, intr, s.rt_cam_board, s.observations.corners, s.observations.board,
                          s.observations.square_m, SIZE)
    return lm, intr, s, oi


def test_at_truth_nothing_moves(truth_problem):
    lm, intr, s, oi = truth_problem
    np.testing.assert_allclose(oi["intrinsics"][0], intr, atol=1e-6)
    d = parameter_shift(oi, np.zeros_like(s.observations.corners))
    assert np.abs(d["intrinsics"]).max() < 1e-9


def test_errors_that_are_a_focal_change_give_that_focal_change(truth_problem):
    lm, intr, s, oi = truth_problem
    obj = mrcal.ref_calibration_object(*s.observations.board, s.observations.square_m).reshape(-1, 3)
    pcam = mrcal.transform_point_rt(s.rt_cam_board[:, None, :], obj[None])
    bumped = intr.copy()
    bumped[0] += 0.05
    err = mrcal.project(pcam, lm, bumped) - mrcal.project(pcam, lm, intr)
    err[~s.observations.seen()] = np.nan
    d = parameter_shift(oi, err)["intrinsics"]
    assert d[0] == pytest.approx(0.05, rel=1e-3)
    assert np.abs(d[1:4]).max() < 1e-4


def test_matches_a_nonlinear_resolve(truth_problem):
    """The first-order lens change against mrcal re-solving with the moved corners, compared where it
    matters, as projection over the central 80% of the image (the rational model's terms can trade
    against each other along a valley of near-equal fits, so the terms themselves are not compared)."""
    from calibration.intrinsics.sensitivity import projection_shift
    from calibration.lens.compare import central_mask, compare
    lm, intr, s, oi = truth_problem
    rng = np.random.default_rng(1)
    seen = s.observations.seen()
    # a systematic error (every corner pushed 0.02 px away from the image centre) plus noise
    c = s.observations.corners
    centre = np.array(intr[2:4])
    away = (c - centre) / np.linalg.norm(c - centre, axis=-1, keepdims=True)
    err = 0.02 * away + rng.normal(0, 0.01, c.shape)
    err[~seen] = np.nan
    d = parameter_shift(oi, err)["intrinsics"]
    grid, lin = projection_shift(lm, intr, d, SIZE)
    re = {k: (np.array(v, copy=True) if isinstance(v, np.ndarray) else v) for k, v in oi.items()}
    re["observations_board"] = oi["observations_board"].copy()
    re["observations_board"][..., :2] += np.nan_to_num(err).reshape(re["observations_board"][..., :2].shape)
    mrcal.optimize(**re)
    moved = re["intrinsics"][0]
    full = compare(lambda v: mrcal.project(np.ascontiguousarray(v), lm, moved),
                   lambda q: mrcal.unproject(np.ascontiguousarray(q), lm, intr, normalize=True), SIZE)
    central = central_mask(grid, SIZE)
    lin_central = float(np.sqrt(np.nanmean(lin[central] ** 2)))
    assert full.central_rms_px > 0.002                 # the error does move the lens
    assert lin_central == pytest.approx(full.central_rms_px, rel=0.25)


def test_refuses_a_problem_it_does_not_handle(truth_problem):
    lm, intr, s, oi = truth_problem
    with pytest.raises(ValueError, match="intrinsics and board poses"):
        parameter_shift(dict(oi, do_optimize_intrinsics_core=False), np.zeros_like(s.observations.corners))


def test_projection_shift_is_zero_for_a_rotation_and_tracks_a_focal_change(truth_problem):
    from calibration.intrinsics.sensitivity import projection_shift
    from calibration.lens.compare import central_mask, compare
    lm, intr, s, oi = truth_problem
    bumped = intr.copy()
    bumped[0] += 0.05
    grid, d = projection_shift(lm, intr, bumped - intr, SIZE)
    c = compare(lambda v: mrcal.project(np.ascontiguousarray(v), lm, bumped),
                lambda q: mrcal.unproject(np.ascontiguousarray(q), lm, intr, normalize=True), SIZE)
    assert np.sqrt(np.nanmean(d ** 2)) == pytest.approx(c.rms_px, rel=0.05)
    assert np.sqrt(np.nanmean(d ** 2)) > 0.005
    # a principal-point shift is mostly a rotation: the fitted rotation takes most of it out
    moved = np.zeros_like(intr)
    moved[2] = 0.1
    grid, d2 = projection_shift(lm, intr, moved, SIZE)
    assert np.isfinite(d2).mean() > 0.99
    central = central_mask(grid, SIZE)
    assert np.sqrt(np.nanmean(d2[central] ** 2)) < 0.05
