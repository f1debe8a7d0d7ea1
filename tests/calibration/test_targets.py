"""--target marker-checkerboard: the target's description, its rendering, and its detector checked
against the rendered truth through truth lenses of four families (the solver's own OPENCV8 is not
among the ones that decide: Kannala-Brandt, stereographic, the published Boson plumb_bob)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from calibration.detect import detect_corners, detect_marker_board, detect_target
from calibration.targets import TargetError, marker_block, marker_centre, parse_target
from calibration.synth.targets_render import MarkerBoard, render_views, target_board
from calibration.synth.truth_families import truth_lens


def test_marker_hides_its_own_3x3_corners():
    block = marker_block((10, 7)).reshape(7, 10)
    assert marker_centre((10, 7)) == (4, 3)
    assert block.sum() == 9 and block[2:5, 3:6].all()
    with pytest.raises(TargetError, match="needs at least 5x5"):
        marker_centre((4, 7))
    with pytest.raises(TargetError, match="unknown target"):
        parse_target("charuco")


def test_rendered_marker_is_the_described_one():
    """The renderer's pattern, sampled at the board points the description names: the marker's
    plain quarters at the board's mean (0), the dot in the top-left quarter with the checker's own
    colour there (the other colour than the squares sharing an edge with it), the squares around
    the marker unchanged."""
    s = 0.04
    for W, H in ((10, 7), (9, 9), (12, 8)):
        b = MarkerBoard(W, H, s)
        mi, mj = marker_centre((W, H))
        q = lambda a, c: float(b.pattern(np.array([(mi + a) * s]), np.array([(mj + c) * s]), 1e-4)[0])
        dot = q(-0.5, -0.5)
        assert abs(dot) > 0.99
        assert q(0.5, -0.5) == pytest.approx(0, abs=1e-6) and q(-0.5, 0.5) == pytest.approx(0, abs=1e-6)
        assert q(0.5, 0.5) == pytest.approx(0, abs=1e-6)
        assert q(-1.5, -0.5) == pytest.approx(-dot) and q(-0.5, -1.5) == pytest.approx(-dot)
        # the plain checkerboard's square at the dot has the dot's colour
        assert target_board("checkerboard", W, H, s).pattern(np.array([(mi - 0.5) * s]),
                                                             np.array([(mj - 0.5) * s]), 1e-4)[0] == pytest.approx(dot)


SQUARE_OFF_PX = 5.0      # the no-edge views' squares are 35 px: a label one square off is 35 px off


def _check_against_truth(det, q, board, tol_px=1.0):
    block = marker_block(board)
    rep = np.isfinite(det.corners[:, 0])
    assert not np.any(rep & block), "a corner of the marker's own squares was reported"
    assert not np.any(rep & np.isnan(q[:, 0])), "a corner reported where the true corner is not in the image"
    err = np.linalg.norm(det.corners[rep] - q[rep], axis=1)
    assert not np.any(err > tol_px), f"{int(np.sum(err > tol_px))} corners more than {tol_px} px from their own " \
                                     f"truth (max {err.max():.2f} px): wrong labels or wild corners"
    return err


@pytest.fixture(scope="module")
def foreign_views():
    """8 views of a 10x7 marker board per truth lens family and difficulty (seeds fixed)."""
    board = MarkerBoard(10, 7, 0.04)
    return {(fam, diff): render_views(truth_lens(fam), board, diff, n=8, seed=seed)
            for fam, diff, seed in (("kannala-brandt", "real", 7), ("boson-published", "real", 9),
                                    ("stereographic", "hard", 8))}


@pytest.mark.slow
@pytest.mark.parametrize("key", [("kannala-brandt", "real"), ("boson-published", "real"), ("stereographic", "hard")])
def test_marker_board_through_foreign_lenses(foreign_views, key):
    """Every reported corner within 1 px of its own true corner, none of the marker's; every view with
    the marker and the squares around it in view and no hand over the board is labelled."""
    board = (10, 7)
    block = marker_block(board)
    around = np.zeros((7, 10), bool)
    around[1:6, 2:7] = True
    labelled, errs = 0, []
    for img, q, occluded in foreign_views[key]:
        det = detect_marker_board(img, board)
        errs.extend(_check_against_truth(det, q, board))
        readable = bool(np.isfinite(q[around.ravel(), 0]).all()) and not occluded.any()
        if readable:
            assert det.detected, f"{key}: the marker is in view but the board was not labelled: {det.reason}"
        labelled += det.detected
    assert labelled >= 4
    rms = float(np.sqrt(np.mean(np.square(errs))))
    assert rms < (0.25 if key[1] == "hard" else 0.06), rms


def _no_edge_views(lens, board: MarkerBoard, distance_m=0.14):
    """Views of a large marker board held so close that it fills the image: no board edge in view."""
    from calibration.synth.poses import BoardView, project_corners
    from platform_tools.rig.frames import rotvec_to_matrix
    centre = board.corners()[marker_block((board.width, board.height))][4]
    views = []
    for tilt, roll_deg, shift in (((0.08, 0.0, 0.0), 20.0, (0.0, 0.0)), ((0.0, 0.1, 0.0), 170.0, (0.02, -0.01)),
                                  ((0.0, 0.0, 0.0), 95.0, (-0.01, 0.01))):
        R = rotvec_to_matrix(np.array(tilt)) @ rotvec_to_matrix(np.array([0.0, 0.0, math.radians(roll_deg)]))
        t = np.array([shift[0], shift[1], distance_m]) - R @ centre
        views.append(BoardView(R, t, project_corners(lens, board, R, t), True))
    return views


@pytest.mark.slow
def test_partial_view_with_no_board_edge_gets_board_coordinates():
    """A 56x44 board filling the image (no corner of its first or last row or column in view), turned
    20, 170 and 95 deg: the plain checkerboard detector cannot place these corners on the board
    (no edge seen); the marker does, no label off (every corner within 5 px of its own truth, where
    one square is 35 px), (0, 0) the board's own corner whatever the roll, and the RMS under 1 px.
    What this test asserts is the labelling: a label off by a square is 35 px off, so the 5 px bound
    catches it while leaving the sub-pixel accuracy to tests/calibration/test_marker_large.py, which
    checks every corner of these views within 1 px (the 2.9 px once measured here was the destriping
    defect, fixed: docs/calibration.md, Targets; measured since: RMS 0.23 / 0.18 / 0.10 px, worst
    0.97 px)."""
    W, H = 56, 44
    board = MarkerBoard(W, H, 0.012)
    lens = truth_lens("kannala-brandt")
    out = render_views(lens, board, "real", views=_no_edge_views(lens, board), seed=3)
    jj, ii = np.divmod(np.arange(W * H), W)
    edge = (ii == 0) | (jj == 0) | (ii == W - 1) | (jj == H - 1)
    for img, q, _ in out:
        assert not np.isfinite(q[edge, 0]).any(), "test set-up: a board edge is in view"
        det = detect_marker_board(img, (W, H))
        err = _check_against_truth(det, q, (W, H), tol_px=SQUARE_OFF_PX)
        print(f"no-edge view: {det.found} of {int(np.isfinite(q[:, 0]).sum()) - 9} corners in view labelled, "
              f"RMS {np.sqrt(np.mean(err ** 2)):.3f} px, max {err.max():.2f} px")
        assert np.sqrt(np.mean(err ** 2)) < 1.0          # measured 0.23 px on the first view (0.65 before the destriping fix)
        # the rest are the image's rim, where these 35 px squares are stretched and cut (measured 83-93%)
        assert det.found > 0.75 * int(np.isfinite(q[:, 0]).sum() - 9), det.reason
        plain = detect_corners(img, (W, H))
        assert not plain.detected and "neither board edge seen" in plain.reason


@pytest.fixture(scope="module")
def whole_board_view():
    board = MarkerBoard(10, 7, 0.04)
    views = render_views(truth_lens("boson-published"), board, "easy", n=3, seed=21)
    img, q, _ = next(v for v in views if np.isfinite(v[1][:, 0]).all())
    return img, q


@pytest.mark.slow
def test_whole_marker_board_is_found_and_labelled(whole_board_view):
    img, q = whole_board_view
    det = detect_target(img, (10, 7), "marker-checkerboard")
    assert det.found == 70 - 9
    err = _check_against_truth(det, q, (10, 7))
    assert float(np.sqrt(np.mean(err ** 2))) < 0.05


@pytest.mark.slow
@pytest.mark.parametrize("board, found", [((12, 9), "10 corners across"), ((11, 7), "10 corners across"),
                                          ((10, 9), "7 corners down"), ((8, 6), "at least 10x7 corners, not 8x6")])
def test_wrong_board_is_refused_with_the_size_found(whole_board_view, board, found):
    """A 10x7 marker board detected as another size: refused, the reason says what was found."""
    img, _ = whole_board_view
    det = detect_marker_board(img, board)
    assert not det.detected
    assert found in det.reason, det.reason


@pytest.mark.slow
def test_a_plain_checkerboard_is_not_taken_for_a_marker_board(synth_set):
    """No marker, no labels: a plain board's corners are never guessed onto a marker board."""
    from tests.calibration.test_detect import image
    folder = synth_set("easy", n=4, seed=0)
    det = detect_marker_board(image(folder, "000.png"), (10, 7))
    assert not det.detected and "marker not found" in det.reason


@pytest.mark.slow
def test_a_corner_no_saddle_fit_confirms_is_not_reported():
    """bench_targets.py --n 10, stereographic truth lens, 'hard', seed 60, view 4: corner (8, 5) of the
    10x7 marker board (34 px squares, faint: mrcal level 3) was reported 1.03 px from its truth. Neither
    saddle fit converged there (from cornerSubPix's estimate nor from the grid's position), so the point
    was cornerSubPix's, unchecked; the image's own saddle, found by the fit started at the truth, is
    0.83 px off it. Such a corner is no longer reported; the rest of the view is, within 1 px."""
    views = render_views(truth_lens("stereographic"), MarkerBoard(10, 7, 0.04), "hard", n=10, seed=60, only=[4])
    assert len(views) == 1
    img, q, occ = views[0]
    assert not occ.any()
    det = detect_marker_board(img, (10, 7))
    assert det.found > 50, det.reason                      # the view is labelled (61 corners before)
    err = _check_against_truth(det, q, (10, 7), tol_px=1.0)
    assert err.max() <= 1.0
