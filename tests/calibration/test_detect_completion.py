"""Completing an anchored board (calibration/detect/complete.py): a missing board corner is predicted
from the labelled grid and kept only where the image shows that very corner."""
from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

from calibration.detect import complete as C
from calibration.detect import detect_corners, detector
from calibration.detect.candidates import find_candidates
from calibration.detect.refine import image_noise

W, H = 7, 7
P0 = np.array([60.0, 50.0])
A = np.array([14.0, 1.5])          # image step of +i
B = np.array([-1.2, 13.0])         # image step of +j
AMBIENT, CONTRAST, NOISE = 7500.0, 80.0, 3.0


def corner(i, j, p0=P0, a=A, b=B):
    return p0 + i * a + j * b


def board_image(factor=None, patch=None, seed=0, size=(200, 180), p0=P0, a=A, b=B, contrast=CONTRAST,
                background=-20.0, frame=0.0):
    """A heated W x H board (W+1 x H+1 squares) under an affine view (corner (i, j) at
    p0 + i a + j b), 4x supersampled, blurred 1.3 px, with pixel noise: 16-bit-like counts. The
    squares sit in a frame ``frame`` squares wide at ambient, the background is ``background``
    counts off ambient. ``factor(m, n)`` scales square (m, n)'s contrast (m, n from -1: the square
    left of / above corner (0, 0) is (-1, -1)); ``patch(x, y, img)`` edits the supersampled image
    (x, y in pixels) before the blur."""
    s = 4
    w, h = size
    y, x = np.mgrid[0:h * s, 0:w * s] / s + (0.5 / s - 0.5)
    M = np.linalg.inv(np.stack([a, b], 1))
    uv = np.einsum("ab,bhw->ahw", M, np.stack([x - p0[0], y - p0[1]]))
    m, n = np.floor(uv[0]), np.floor(uv[1])
    on = (m >= -1) & (m <= W - 1) & (n >= -1) & (n <= H - 1)
    framed = (uv[0] >= -1 - frame) & (uv[0] < W + frame) & (uv[1] >= -1 - frame) & (uv[1] < H + frame)
    sign = np.where((m + n) % 2 == 0, 1.0, -1.0)
    k = np.ones_like(sign)
    if factor is not None:
        for mm in range(-1, W):
            for nn in range(-1, H):
                k[(m == mm) & (n == nn)] = factor(mm, nn)
    img = np.where(on, AMBIENT + 0.5 * contrast * sign * k, np.where(framed, AMBIENT, AMBIENT + background))
    if patch is not None:
        patch(x, y, img)
    img = cv2.resize(img.astype(np.float32), (w, h), interpolation=cv2.INTER_AREA)
    img = cv2.GaussianBlur(img, (0, 0), 1.3)
    return img + np.random.default_rng(seed).normal(0, NOISE, img.shape).astype(np.float32)


def run_complete(img, missing, **view):
    """complete() on the exact grid of the board without the labels in ``missing``."""
    noise = image_noise(img)
    _, _, S, _ = find_candidates(img, noise=noise)
    ij = np.array([(i, j) for j in range(H) for i in range(W) if (i, j) not in missing])
    xy = np.array([corner(i, j, **view) for i, j in ij])
    return C.complete(img, S, xy, ij, (W, H), noise)


def test_faint_board_corner_the_growth_refuses_is_added_with_its_label():
    """A small board (8 px steps) whose contrast falls towards its bottom-right corner, in front of
    a warm background: the growth refuses corner (6, 6) (its weakest square, on the local-contrast
    image, is below the limit: the background pulls the local mean), the completion predicts it
    from the grid, finds the saddle there and adds it with label (6, 6) at its true place."""
    from calibration.detect.grow import grow
    view = dict(p0=np.array([40.0, 30.0]), a=np.array([8.0, 0.8]), b=np.array([-0.64, 7.6]))

    def rim(mm, nn):
        return max(1.0 - 0.15 * max(mm + nn - 7, 0), 0.3)
    img = board_image(rim, size=(140, 120), contrast=120.0, background=150.0, frame=0.3, **view)
    target = (W - 1, H - 1)
    noise = image_noise(img)
    _, g, S, _ = find_candidates(img, noise=noise)
    ij = np.array([(i, j) for j in range(H) for i in range(W) if (i, j) != target])
    xy = np.array([corner(i, j, **view) for i, j in ij])
    _, grown, _ = grow(g, S, xy, ij, np.ones(len(xy)), (W, H))
    assert target not in {tuple(t) for t in grown.tolist()}
    new_xy, new_ij, added = C.complete(img, S, xy, ij, (W, H), noise)
    assert [tuple(t) for t in new_ij[added].tolist()] == [target]
    # (within 1 px: the squares around it are unequal, 30-55 % of the board's contrast, which
    # biases any saddle estimate a little; a neighbour is 8 px away)
    assert np.linalg.norm(new_xy[added][0] - corner(*target, **view)) < 1.0
    # the labelled corners are handed back untouched
    np.testing.assert_allclose(new_xy[~added], xy)
    assert np.array_equal(new_ij[~added], ij)


def test_missing_far_column_and_hole_are_filled_round_by_round():
    """A whole missing column (extrapolated from the two next to it) and an interior hole of four
    corners come back, each at its true place with its own label."""
    img = board_image(seed=1)
    missing = {(0, j) for j in range(H)} | {(3, 3), (4, 3), (3, 4), (4, 4)}
    xy, ij, added = run_complete(img, missing)
    assert {tuple(t) for t in ij[added].tolist()} == missing
    err = np.linalg.norm(xy - np.array([corner(i, j) for i, j in ij]), axis=1)
    assert err.max() < 0.3


def test_covered_corner_with_a_fake_saddle_next_to_it_is_not_added():
    """The place of corner (3, 3) covered by a warm hand, with a small warm object's X-shaped
    corner 1 px from the predicted place: the saddle fit finds a saddle right there, but the four
    squares around it are not this board's checker (a fake saddle), so nothing is added."""
    c = corner(3, 3) + [1.0, 0.0]

    def hand_and_clutter(x, y, img):
        hand = np.hypot(x - corner(3, 3)[0], y - corner(3, 3)[1]) < 11.0
        img[hand] = AMBIENT + 60.0
        small = (np.abs(x - c[0]) < 3.5) & (np.abs(y - c[1]) < 3.5)
        img[small] = np.where((x[small] - c[0]) * (y[small] - c[1]) > 0, AMBIENT + 120.0, AMBIENT + 10.0)

    img = board_image(patch=hand_and_clutter, seed=2)
    fit = C._saddle_near(img, cv2.GaussianBlur(img, (0, 0), 1.5), find_candidates(img)[2], corner(3, 3)[None],
                         np.array([1.4]), np.array([13.0]))
    assert np.isfinite(fit[0, 0]), "the fake saddle should be there for the test to mean something"
    _, ij, added = run_complete(img, {(3, 3)})
    assert not added.any()
    assert (3, 3) not in {tuple(t) for t in ij.tolist()}


def test_saddle_of_the_wrong_parity_is_not_added():
    """The four squares around corner (3, 3) inverted (a saddle at the right place, the wrong way
    round for this grid's label): not taken for corner (3, 3)."""
    def inverted(mm, nn):
        return -1.0 if (mm, nn) in ((2, 2), (3, 2), (2, 3), (3, 3)) else 1.0
    img = board_image(inverted, seed=3)
    _, ij, added = run_complete(img, {(3, 3)})
    assert not added.any()


def test_corner_half_under_a_hand_is_not_added():
    """Corner (3, 3) with the squares below it under an occluder (at the board's mean level) whose
    edge runs just below the corner, and a small X of the board's own parity right at the corner
    (fingers, clutter): the saddle fit converges there, the squares above alternate the right way,
    but the half under the occluder is flat: not added."""
    c = corner(3, 3)
    M = np.linalg.inv(np.stack([A, B], 1))

    def hand(x, y, img):
        u, v = np.einsum("ab,bhw->ahw", M, np.stack([x - P0[0], y - P0[1]]))
        under = (v > 3.08) & (np.hypot(x - c[0], y - c[1]) < 22.0)
        img[under] = AMBIENT
        small = (np.abs(x - c[0]) < 4.0) & (np.abs(y - c[1]) < 4.0)
        sign = np.where((np.floor(u) + np.floor(v)) % 2 == 0, 1.0, -1.0)
        img[small] = AMBIENT + 0.5 * CONTRAST * sign[small]

    img = board_image(patch=hand, seed=4)
    fit = C._saddle_near(img, cv2.GaussianBlur(img, (0, 0), 1.5), find_candidates(img)[2], c[None],
                         np.array([1.4]), np.array([13.0]))
    assert np.linalg.norm(fit[0] - c) < 1.0, "the saddle should be there for the test to mean something"
    _, _, added = run_complete(img, {(3, 3)})
    assert not added.any()


@pytest.fixture(scope="module")
def hard_018(synth_set):
    folder = synth_set("hard", n=19, seed=300, only=[18])
    truth = json.loads((folder / "truth.json").read_text())
    im = truth["images"][0]
    assert im["file"] == "018.png"
    q = np.array([c if c is not None else [np.nan, np.nan] for c in im["corners"]], float)
    return cv2.imread(str(folder / im["file"]), cv2.IMREAD_UNCHANGED), q, im


@pytest.mark.slow
def test_bench_board_with_one_faint_corner_is_now_complete(hard_018, monkeypatch):
    """'hard' seed 300, image 018 (the bench's hard set): a fully visible, steep, blurred board
    whose far top corner (7, 0) the growth never added (its squares too faint for the weakest-square
    limits). With the completion the board is complete and every corner within 1 px of the truth;
    without it, that corner is missing."""
    img, q, im = hard_018
    assert im["visible"] == 70 and not im["occluded"]
    det = detect_corners(img, (10, 7))
    assert det.complete, det.found
    err = np.linalg.norm(det.corners - q, axis=1)
    assert err.max() < 1.0, err.max()
    monkeypatch.setattr(detector, "complete", lambda f, S, xy, ij, board, noise: (xy, ij, np.zeros(len(xy), bool)))
    before = detect_corners(img, (10, 7))
    assert not before.complete
    assert before.found == 69
