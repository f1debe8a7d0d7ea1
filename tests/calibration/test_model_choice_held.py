"""Kannala-Brandt with its last terms held at 0 where the four-term fit folds inside the image
(calibration/thermal/lens_choice.py, calibration/intrinsics/opencv_solver.py ``fixed_terms``).

The corners are projected in closed form through a stereographic truth lens (not a family any
candidate has) at the rig's nominal focal length, with 0.35 px of noise, from 30 board poses that keep
every corner within 45 deg of the axis while the image corners are at about 64 deg: coverage as sparse
as the bench's 8-bit "hard" sets, where the four-term fit folded just inside the image corners and the
default fell back to OPENCV8, 4.45 px (seed 11) and 24 px (seed 23) off over the whole image. No image
is rendered and no detector runs: the rule is judged on its own."""
from __future__ import annotations

import cv2
import numpy as np
import pytest

from calibration.intrinsics import mrcal_solver, opencv_solver
from calibration.intrinsics.observations import BoardObservations
from calibration.lens import kannala_brandt as kb
from calibration.lens.compare import compare
from calibration.synth.truth_families import truth_lens
from calibration.thermal import lens_choice as lc
from calibration.thermal.lens_check import solution_health

W = H = 8
SQUARE_M = 0.04
MAX_DEG = 45.0
NOISE_PX = 0.35
SEED = 0            # the first draw tried in which the four-term fit folds (asserted below)
WHOLE_PX = 1.0      # issue 14's hard target is 0.5 px on 40 rendered images; these are 30 sparse views


@pytest.fixture(scope="module")
def setup():
    from platform_tools.rig import load_rig

    from calibration.commands.thermal import nominal_corner_angle_deg
    rig = load_rig()
    lens = truth_lens("stereographic", rig=rig)
    rng = np.random.default_rng(SEED)
    board = np.array([[i * SQUARE_M, j * SQUARE_M, 0] for j in range(H) for i in range(W)], float) \
        - [3.5 * SQUARE_M, 3.5 * SQUARE_M, 0]
    views = []
    while len(views) < 30:
        axis = rng.normal(size=3)
        R = cv2.Rodrigues(axis / np.linalg.norm(axis) * np.radians(rng.uniform(0, 50)))[0]
        z = rng.uniform(0.35, 0.8)
        off, az = np.radians(rng.uniform(0, MAX_DEG)), rng.uniform(0, 2 * np.pi)
        p = board @ R.T + z * np.array([np.tan(off) * np.cos(az), np.tan(off) * np.sin(az), 1.0])
        if (p[:, 2] <= 0).any() or np.degrees(np.arccos(p[:, 2] / np.linalg.norm(p, axis=1))).max() > MAX_DEG:
            continue
        q = lens.project(p) + rng.normal(scale=NOISE_PX, size=(len(p), 2))
        w, h = lens.size
        if ((q[:, 0] > 0) & (q[:, 0] < w - 1) & (q[:, 1] > 0) & (q[:, 1] < h - 1)).all():
            views.append(q)
    obs = BoardObservations([f"{k:03d}.png" for k in range(len(views))], np.array(views),
                            np.ones((len(views), W * H)), (W, H), SQUARE_M, tuple(lens.size))
    return lens, obs, float(lens.fx), nominal_corner_angle_deg(rig)


def _whole_px(sol, lens) -> float:
    if sol.lensmodel == kb.NAME:
        def project(v, p=sol.intrinsics):
            return kb.project(v, p)
    else:
        import mrcal

        def project(v, s=sol):
            return mrcal.project(np.ascontiguousarray(v), s.lensmodel, s.intrinsics)
    return compare(project, lens.unproject, lens.size).rms_px


def _default(obs, focal, nominal, held: bool):
    o8 = mrcal_solver.solve(obs, lensmodel="LENSMODEL_OPENCV8", focal_px=focal)
    four = opencv_solver.solve(obs, focal_px=focal)
    return lc.choose_default(
        o8, four, lambda: mrcal_solver.solve(obs, lensmodel="LENSMODEL_OPENCV5", focal_px=focal), nominal,
        (lambda n: opencv_solver.solve(obs, focal_px=focal, fixed_terms=n)) if held else None)


def test_where_the_four_term_fit_folds_the_default_keeps_kannala_brandt_with_terms_held(setup):
    lens, obs, focal, nominal = setup
    four = opencv_solver.solve(obs, focal_px=focal)
    h4 = solution_health(four, min_corner_angle_deg=nominal)
    assert not h4.ok, "the draw no longer folds: the test does not test the rule"
    before = _default(obs, focal, nominal, held=False)
    after = _default(obs, focal, nominal, held=True)
    assert after.lensmodel == kb.NAME and after.fixed_terms >= 1
    assert solution_health(after, min_corner_angle_deg=nominal).ok
    assert any("held at 0 stands in for the four-term fit" in n for n in after.notes)
    kb_status = [c for c in after.model_choice["candidates"] if c["model"] == lc.KB][0]
    assert kb_status["healthy"] and kb_status["held_terms"] == after.fixed_terms
    e_after, e_before, e_four = _whole_px(after, lens), _whole_px(before, lens), _whole_px(four, lens)
    assert e_after < WHOLE_PX, (e_after, e_before, e_four)
    assert e_after < e_before and e_after < e_four


def test_the_held_terms_stay_at_zero_in_every_solve(setup):
    _, obs, focal, _ = setup
    for n in (1, 2):
        s = opencv_solver.solve(obs, focal_px=focal, fixed_terms=n)
        assert s.fixed_terms == n
        assert np.all(s.intrinsics[8 - n:] == 0.0) and np.all(s.intrinsics[4:8 - n] != 0.0)
        again = opencv_solver.resolve(s, obs)           # the warm re-solve (circle grids' bias rounds)
        assert np.all(again.intrinsics[8 - n:] == 0.0)
        from calibration.intrinsics.crossval import solve_subset
        project, _ = solve_subset(s, np.arange(0, obs.n, 2))     # the halves and the held-out folds
        v = np.array([[0.7, 0.0, 0.7]])                            # 45 deg: where k4 would act
        p = kb.project(v, s.intrinsics)
        assert np.isfinite(project(v)).all() and np.linalg.norm(project(v) - p) < 5.0
    with pytest.raises(ValueError, match="fixed_terms 3"):
        opencv_solver.solve(obs, focal_px=focal, fixed_terms=3)


def test_a_healthy_four_term_fit_is_not_replaced(setup):
    _, obs, focal, nominal = setup
    called = []
    o8 = mrcal_solver.solve(obs, lensmodel="LENSMODEL_OPENCV8", focal_px=focal)
    healthy = opencv_solver.solve(obs, focal_px=focal, fixed_terms=2)     # a healthy Kannala-Brandt (asserted)
    assert solution_health(healthy, min_corner_angle_deg=nominal).ok
    lc.choose_default(o8, healthy, lambda: None, nominal, lambda n: called.append(n))
    assert called == []
