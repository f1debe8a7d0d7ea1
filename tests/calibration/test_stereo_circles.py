"""`calibrate thermal-stereo` with a circle grid: each disc's centroid bias taken off in the pair's solve
(calibration/stereo/centroids.py), as the mono solve takes it off.

The observations are each disc's imaged-area centroid in each camera, computed by the independent path of
tests/calibration/test_circle_bias.py (the area integral of the projected disc with the Jacobian
determinant by finite differences; not the rim polygon disc_centroid_bias uses), through two closed-form
stereographic truth lenses (not mrcal's code; the mono models given to the solve are those lenses as
LENSMODEL_STEREOGRAPHIC, held, so what moves is the pose); the truth pose is the rig's designed one moved
by 1.7 mm and 0.6 deg. Close, steep views (0.28-0.5 m, tilted 35-60 deg) of a 10 x 9 asymmetric grid of
0.04 m, 12 mm discs: the bias differs between the two cameras' views of one board, and a pose solved
from the raw centroids absorbs the difference."""
from __future__ import annotations

import numpy as np
import pytest

from calibration.stereo.centroids import solve_pair_corrected
from calibration.stereo.pairs import StereoObservations
from calibration.stereo.solve import solve_pair
from calibration.synth.circles_render import circle_board
from platform_tools.rig.frames import Pose, rotvec_to_matrix

from .test_circle_bias import area_centroids
from .test_thermal_stereo import as_model, cad_pose, truth_lenses, truth_pose

KIND, BOARD, SPACING = "asymmetric-circle-grid", (10, 9), 0.04
N_VIEWS = 8


def steep_pair_views(lenses, T_left_right: Pose, board, n: int, seed: int):
    """n (R, t) board -> left camera, the whole board at least 6 px inside both images."""
    rng = np.random.default_rng(seed)
    T_right_left = T_left_right.inverse()
    pts = board.corners()
    out = []
    while len(out) < n:
        az, el = np.radians(rng.uniform(-25, 25)), np.radians(rng.uniform(-20, 20))
        v = np.array([np.tan(az), np.tan(el), 1.0])
        v /= np.linalg.norm(v)
        axis = rng.normal(size=3)
        axis[2] = 0
        R = rotvec_to_matrix(axis / np.linalg.norm(axis) * np.radians(rng.uniform(35, 60)))
        t = rng.uniform(0.28, 0.5) * v + np.array([0.06, 0.0, 0.0]) - R @ board.centre()
        pl = pts @ R.T + t
        pr = T_right_left.apply(pl * 1000.0) / 1000.0
        if min(pl[:, 2].min(), pr[:, 2].min()) < 0.05:
            continue
        W, H = lenses[0].size
        if all(np.all((q > 6) & (q < np.array([W - 7, H - 7]))) for q in (lenses[0].project(pl),
                                                                          lenses[1].project(pr))):
            out.append((R, t))
    return out


@pytest.fixture(scope="module")
def pair():
    lenses = truth_lenses()
    T_true = truth_pose(cad_pose())
    T_right_left = T_true.inverse()
    b = circle_board(KIND, *BOARD, SPACING)
    present = b.present()
    rot_rl = T_right_left.R
    ql, qr = [], []
    for R, t in steep_pair_views(lenses, T_true, b, N_VIEWS, seed=4):
        t_r = T_right_left.apply((R @ b.centre() * 0 + t) * 1000.0) / 1000.0     # board origin in the right camera
        for lens, RR, tt, out in ((lenses[0], R, t, ql), (lenses[1], rot_rl @ R, t_r, qr)):
            c = area_centroids(lens, RR, tt, b.corners(), b.radius)
            c[~present] = np.nan
            out.append(c)
    ql, qr = np.array(ql), np.array(qr)
    w = np.where(np.isfinite(ql[..., 0]), 1.0, 0.0)
    obs = StereoObservations([f"{k:03d}" for k in range(N_VIEWS)], ql, qr, w, w.copy(), BOARD, SPACING)
    models = tuple(as_model(lens) for lens in lenses)
    return obs, models, T_true, b


def pose_error(sol, T_true: Pose) -> tuple[float, float]:
    D = T_true.inverse() @ sol.T_left_right
    return float(np.linalg.norm(sol.T_left_right.t - T_true.t)), float(D.angle_deg())


@pytest.mark.slow
def test_the_pair_solved_from_corrected_centres_moves_to_the_true_pose(pair):
    """Raw centroids put the right camera 0.1 mm or more and 0.01 deg or more off the truth (measured
    below); with the bias taken off in both cameras the pose comes back within a tenth of that and the
    residual falls to the integration's own error."""
    obs, models, T_true, b = pair
    seed = T_true.inverse().rt(metres=True) + np.array([0.002, -0.003, 0.001, 0.003, 0.002, -0.002])
    raw = solve_pair(obs, models, seed)
    sol, centres, rounds = solve_pair_corrected(obs, raw, b.radius)
    e_raw, e_cor = pose_error(raw, T_true), pose_error(sol, T_true)
    print(f"raw: {e_raw[0]:.4f} mm {e_raw[1]:.5f} deg rms {raw.rms_px}; corrected: {e_cor[0]:.5f} mm "
          f"{e_cor[1]:.6f} deg rms {sol.rms_px}; rounds {rounds['rounds']} bias max {rounds['bias_max_px']:.3f}")
    assert rounds["bias_max_px"] > 0.2                       # the bias these views carry
    assert e_raw[0] > 0.02 and e_raw[1] > 0.002
    assert e_cor[0] < 0.2 * e_raw[0] and e_cor[1] < 0.2 * e_raw[1]
    assert max(sol.rms_px) < 0.2 * min(raw.rms_px)
    assert rounds["converged"] and rounds["rounds"] <= 6
    assert centres.left.shape == obs.left.shape and np.isnan(centres.left[:, ~b.present()]).all()


@pytest.mark.slow
def test_a_disc_set_aside_as_an_outlier_is_corrected_too(pair):
    """One disc of view 2's left image moved 2 px: mrcal's outlier rejection sets it aside in round 0
    (with it, on these noise-free centroids, the most biased discs: 29 in all, counted among the discs
    seen, not the grid's 720 empty lattice points, 45 per image); their centres are still corrected, as every
    detected disc is, since the epipolar error is measured on all of them."""
    obs, models, T_true, b = pair
    moved = obs.subset(np.arange(obs.n))
    k = int(np.flatnonzero(b.present())[20])
    moved.left[2, k] += [2.0, 0.0]
    seed = T_true.inverse().rt(metres=True)
    raw = solve_pair(moved, models, seed)
    W = BOARD[0]
    assert raw.optimization_inputs["observations_board"][2 * 2, k // W, k % W, 2] <= 0     # set aside
    n_seen = int(np.isfinite(moved.left[..., 0]).sum() + np.isfinite(moved.right[..., 0]).sum())
    assert 1 <= raw.n_outliers < 0.1 * n_seen, raw.n_outliers
    _, centres, _ = solve_pair_corrected(moved, raw, b.radius)
    seen = np.isfinite(moved.left[..., 0])
    assert (np.isfinite(centres.left[..., 0]) == seen).all()
    shift = np.linalg.norm(centres.left - moved.left, axis=-1)[seen]
    assert shift.min() > 1e-4, shift.min()            # every detected disc moved by its bias
    assert shift.max() < 1.0


@pytest.mark.parametrize("extra, match", [
    (["--circle-radius", "0.01"], "--circle-radius goes with --target circle-grid"),
    (["--target", "circle-grid", "--circle-radius", "0.03"], "less than half the spacing"),
])
def test_a_circle_radius_the_board_cannot_have_is_one_line_exit_2(tmp_path, capsys, extra, match):
    from calibration.cli import main
    out = tmp_path / "out"
    code = main(["thermal-stereo", "--left", str(tmp_path / "l.cameramodel"), "--right", str(tmp_path / "r.cameramodel"),
                 "--images", str(tmp_path), "--board", "10x7", "--square", "0.04", "--out", str(out)] + extra)
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and match in err[0], err
    assert not out.exists()


# ---------------------------------------------------------------- rendered pairs, through the detector
# The same kind of views (steep_pair_views, seed 4, 10 poses) rendered as images: the asymmetric grid's
# hot discs drawn by calibration/synth/circles_render.py through each camera's stereographic truth lens
# at the truth pose ("easy" look, calibration/synth's microbolometer), detected by the circle-grid
# detector inside `calibrate thermal-stereo`, run as a user runs it, once with the correction (the
# default) and once with --no-centroid-correction. Measured over five pose draws (seeds 4-8, 8 poses;
# docs/calibration.md, "calibrate thermal-stereo"): raw 0.016-0.021 mm and 0.0016-0.0044 deg from the
# truth pose, corrected 0.0018-0.0051 mm and 0.00013-0.0007 deg (2.2 to 14 x closer), the RMS
# residual 0.013-0.016 px raw, 0.0045-0.0073 px corrected.
N_RENDERED = 10


@pytest.fixture(scope="module")
def rendered_pairs(tmp_path_factory):
    """root with set/left, set/right (NNN.png, 16-bit), left.cameramodel and right.cameramodel (the
    truth lenses), and the truth pose."""
    import cv2

    from calibration.synth.difficulty import level
    from calibration.synth.poses import BoardView
    from calibration.synth.render import render_image
    from calibration.synth.sensor import Sensor
    from calibration.synth.truth_files import write_cameramodel
    root = tmp_path_factory.mktemp("stereo_circles")
    lenses = truth_lenses()
    T_true = truth_pose(cad_pose())
    T_right_left = T_true.inverse()
    b = circle_board(KIND, *BOARD, SPACING)
    views = steep_pair_views(lenses, T_true, b, N_RENDERED, seed=4)
    diff = level("easy")
    for side, lens in (("left", lenses[0]), ("right", lenses[1])):
        (root / "set" / side).mkdir(parents=True)
        sensor = Sensor.make(np.random.default_rng([4, len(side)]), lens.size[::-1], diff)
        for k, (R, t) in enumerate(views):
            if side == "right":
                R, t = T_right_left.R @ R, T_right_left.R @ t + T_right_left.t / 1000.0
            q = lens.project(b.corners() @ R.T + t)
            img, _, _ = render_image(np.random.default_rng([4, k, len(side)]), lens, b, BoardView(R, t, q, False),
                                     diff, sensor)
            cv2.imwrite(str(root / "set" / side / f"{k:03d}.png"), img)
        write_cameramodel(root / f"{side}.cameramodel", lens, f"truth lens of the {side} camera")
    return root, T_true


def run_thermal_stereo(root, out, capsys, *extra):
    """(exit code, stereo.json as --json prints it, the right camera's pose read back from
    right.cameramodel)."""
    import json

    import mrcal

    from calibration.cli import main
    code = main(["thermal-stereo", "--left", str(root / "left.cameramodel"),
                 "--right", str(root / "right.cameramodel"), "--images", str(root / "set"), "--board", f"{BOARD[0]}x{BOARD[1]}", "--square", str(SPACING),
                 "--target", KIND, "--out", str(out), "--json", "-q", *extra])
    printed = capsys.readouterr()
    assert code == 0, printed.err
    rt = mrcal.cameramodel(str(out / "right.cameramodel")).extrinsics_rt_fromref()
    return json.loads(printed.out), Pose.from_rt(rt, metres=True).inverse()


def pose_error_T(T: Pose, T_true: Pose) -> tuple[float, float]:
    return float(np.linalg.norm(T.t - T_true.t)), float((T_true.inverse() @ T).angle_deg())


@pytest.mark.slow
def test_rendered_pairs_solve_closer_to_the_truth_with_the_correction(rendered_pairs, tmp_path, capsys):
    """On rendered images the detected centroids carry the bias and the detector's own error: raw, the
    pose is at least 0.01 mm and 0.001 deg off (measured 0.0225 mm, 0.0048 deg on these images);
    corrected, at most half of that on both (measured 0.0035 mm, 0.0005 deg), with the residual and the
    epipolar error down too, on the same views."""
    root, T_true = rendered_pairs
    cor, T_cor = run_thermal_stereo(root, tmp_path / "corrected", capsys)
    raw, T_raw = run_thermal_stereo(root, tmp_path / "raw", capsys, "--no-centroid-correction")
    e_cor, e_raw = pose_error_T(T_cor, T_true), pose_error_T(T_raw, T_true)
    print(f"raw {e_raw[0]:.4f} mm {e_raw[1]:.5f} deg rms {raw['rms_px']} epi {raw['epipolar']['rms_px']:.4f}; "
          f"corrected {e_cor[0]:.4f} mm {e_cor[1]:.5f} deg rms {cor['rms_px']} epi {cor['epipolar']['rms_px']:.4f}")
    assert raw["centroid_correction"] is None
    c = cor["centroid_correction"]
    assert c["converged"] and c["bias_max_px"] > 0.2
    assert cor["shared_views"] == raw["shared_views"] >= 5
    assert e_raw[0] > 0.01 and e_raw[1] > 0.001                   # the bias shows in the raw pose
    assert e_cor[0] < 0.5 * e_raw[0] and e_cor[1] < 0.5 * e_raw[1]
    assert max(cor["rms_px"].values()) < 0.6 * min(raw["rms_px"].values())
    assert cor["epipolar"]["rms_px"] < raw["epipolar"]["rms_px"]
    # the outliers are points mrcal set aside, not the asymmetric grid's empty lattice points
    n_discs = int(circle_board(KIND, *BOARD, SPACING).present().sum())
    assert cor["outliers"] == raw["outliers"] < 0.05 * cor["shared_views"] * 2 * n_discs
