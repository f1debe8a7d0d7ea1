"""The detector on the 'hard' boards bench/bench_calib_lenses.py lost (issue 14 item 4: at least 85 %
complete boards in hard conditions on every truth lens): 8x8 board, 0.04 m, seed 11, rendered through
the stereographic truth lens (calibration/synth/truth_families.py: closed form, not the solver's
family), each image checked against its own rendered truth."""
from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

from calibration.detect import detect_corners

BOARD = (8, 8)


@pytest.fixture(scope="module")
def stereographic_hard(tmp_path_factory):
    """Images 001, 010 and 024 of the bench's 40-image stereographic 'hard' set (each image has its
    own random stream: the same pixels as in the whole set)."""
    from calibration.synth import render_dataset
    from calibration.synth.truth_families import truth_lens
    out = tmp_path_factory.mktemp("stereo_hard") / "set"
    render_dataset(out, n=40, difficulty="hard", board=BOARD, square=0.04, seed=11,
                   lens=truth_lens("stereographic"), show_progress=False, only=[1, 10, 24])
    images = {}
    for im in json.loads((out / "truth.json").read_text())["images"]:
        q = np.array([c if c is not None else [np.nan, np.nan] for c in im["corners"]], float)
        images[im["file"]] = (cv2.imread(str(out / im["file"]), cv2.IMREAD_UNCHANGED), q, im)
    return images


def _errors(det, q):
    rep = np.isfinite(det.corners[:, 0])
    assert not np.any(rep & np.isnan(q[:, 0])), "a corner reported where the true corner is outside the image"
    return np.linalg.norm(det.corners[rep] - q[rep], axis=1)


@pytest.mark.slow
@pytest.mark.parametrize("name, why", [
    # cooled, 1.54 K, 23.5 px squares: the last row's three corners at the board's corner in front of
    # a hot object; the local-contrast image's saddle response there was 0.03-0.04 of the grid's
    # (the object's contrast squashes it), below the completion's 0.05 floor, while the checker on
    # the destriped image was 0.74-0.81 of the grid's amplitude with clean halves
    ("001.png", "saddle response judged on the destriped image"),
    # heated, 1.69 K, 28.7 px squares: corner (0, 0) 7 px below the image's top edge, on a board
    # foreshortened there (a 15 px step down): the completion's sampling frame had to shrink to
    # 0.38 of its size to stay in the image, and 0.6 was the floor
    ("024.png", "sampling frame shrunk to 0.35 near the image edge"),
])
def test_fully_visible_hard_boards_are_found_complete(stereographic_hard, name, why):
    img, q, im = stereographic_hard[name]
    assert im["visible"] == 64 and not im["occluded"]
    det = detect_corners(img, BOARD)
    err = _errors(det, q)
    assert det.complete, f"{name} ({why}): {det.found} of 64 corners ({det.reason})"
    assert err.max() <= 1.0, f"{name}: {int(np.sum(err > 1))} corners more than 1 px off (max {err.max():.2f})"


@pytest.mark.slow
def test_a_steep_board_at_the_image_edge_is_found_complete(stereographic_hard):
    """Image 010 (cooled, 3.56 K, the whole board in view at the right edge, lines crossing at
    39-57 deg, steps from 16 to 60 px): the candidates' ring tests miss 18 of its 64 corners and the
    linking labelled the rest inconsistently (regions one to three squares apart within one grid), so
    the view was refused ("partial board ... neither board edge seen"). With the regions that disagree
    with the largest dropped before the growth (calibration/detect/regions.py), the growth finds those
    corners again from the grid: complete, every corner within 1 px of its own truth."""
    img, q, im = stereographic_hard["010.png"]
    assert im["visible"] == 64 and not im["occluded"]
    det = detect_corners(img, BOARD)
    err = _errors(det, q)
    assert det.complete, f"{det.found} of 64 corners ({det.reason})"
    assert err.max() <= 1.0, f"{int(np.sum(err > 1))} corners more than 1 px off (max {err.max():.2f})"
