"""Frame selection from a recording (calibration/frames/select.py): pure functions, on images drawn
here with OpenCV (not the project's renderer) and on corner sets laid out by hand."""
from __future__ import annotations

import cv2
import numpy as np

from calibration.frames import board_sharpness, coverage_greedy, ffc_mask, frozen_mask, sharp_mask, sharpness


def _checker(shift=0, size=(256, 320), step=24, hot=7900, cold=7500):
    yy, xx = np.mgrid[0:size[0], 0:size[1]]
    img = np.where(((xx + shift) // step + yy // step) % 2 == 0, hot, cold).astype(np.float32)
    return img


def test_blurred_frames_fall_below_the_recordings_own_median():
    rng = np.random.default_rng(0)
    frames, blurred = [], []
    for k in range(12):
        img = cv2.GaussianBlur(_checker(k), (0, 0), 0.8)
        if k in (3, 7, 8):                       # motion blur: a 15 px smear along x
            img = cv2.blur(img, (15, 1))
            blurred.append(k)
        frames.append(np.clip(img + rng.normal(0, 8, img.shape), 0, 65535).astype(np.uint16))
    v = np.array([sharpness(f) for f in frames])
    keep = sharp_mask(v)
    assert set(np.flatnonzero(~keep)) == set(blurred)
    # a hotter board is not sharper: the score is scaled by the frame's own contrast
    hot = cv2.GaussianBlur(_checker(0, hot=9500), (0, 0), 0.8)
    assert abs(sharpness(hot) / sharpness(cv2.GaussianBlur(_checker(0), (0, 0), 0.8)) - 1) < 0.05
    assert sharpness(np.full((10, 10), 7, np.uint16)) == 0.0


def test_frozen_frames_and_ffc_spans():
    a, b = _checker(0).astype(np.uint16), _checker(5).astype(np.uint16)
    assert frozen_mask([a, b, b.copy(), b, a]).tolist() == [False, False, True, True, False]
    t = np.arange(10) * 33_333_333
    m = ffc_mask(t, [(100_000_000, 150_000_000)], margin_ns=40_000_000)
    assert np.flatnonzero(m).tolist() == [2, 3, 4, 5]
    assert not ffc_mask(t, []).any()


def _board(cx, cy, half=40.0, n=5):
    g = np.linspace(-half, half, n)
    xx, yy = np.meshgrid(g, g)
    return np.stack([xx.ravel() + cx, yy.ravel() + cy], axis=1)


def test_coverage_greedy_covers_the_image_before_repeating_the_centre():
    W, H = 640, 512
    centre = [_board(320, 256) for _ in range(20)]
    corners_ = [_board(x, y) for x, y in ((60, 50), (580, 50), (60, 460), (580, 460))]
    edges = [_board(320, 40), _board(40, 256)]
    frames = centre[:10] + [corners_[0], None] + centre[10:] + corners_[1:] + edges + [_board(320, 256)[:3]]
    chosen = coverage_greedy(frames, (W, H), max_frames=8)
    assert len(chosen) == 8 and len(set(chosen)) == 8
    picked_corners = {k for k in chosen if frames[k] is not None and
                      (abs(frames[k][:, 0].mean() - 320) > 200 and abs(frames[k][:, 1].mean() - 256) > 150)}
    assert len(picked_corners) == 4                       # every image corner
    assert sum(1 for k in chosen if frames[k] is not None and
               np.allclose(frames[k].mean(axis=0), (320, 256))) <= 2   # the centre at most twice
    assert 11 not in chosen and len(frames) - 1 not in chosen        # no board / too few corners
    # nothing left to add: it stops before max_frames
    assert len(coverage_greedy(centre, (W, H), max_frames=20)) < 20


def test_board_sharpness_does_not_grow_with_the_boards_size_in_the_frame():
    """Whole-frame sharpness grows with how much of the frame the board fills; inside the board's
    hull it does not, and a smeared board is below a sharp one whatever its size."""
    def frame(step, n, blur):
        img = np.full((512, 640), 7500, np.float32)
        x0, y0 = 100, 80
        yy, xx = np.mgrid[0:n * step, 0:n * step]
        img[y0:y0 + n * step, x0:x0 + n * step] = np.where((xx // step + yy // step) % 2 == 0, 7900, 7500)
        img = cv2.GaussianBlur(img, (0, 0), 0.8)
        if blur:
            img = cv2.blur(img, (9, 1))
        g = np.arange(1, n) * step
        corners = np.array([(x0 + a, y0 + b) for b in g for a in g], float)
        return img, corners
    small, big = frame(16, 6, False), frame(16, 20, False)
    assert sharpness(big[0]) > 3 * sharpness(small[0])
    assert abs(board_sharpness(*big) / board_sharpness(*small) - 1) < 0.35
    assert board_sharpness(*frame(16, 20, True)) < 0.3 * board_sharpness(*small)
    assert board_sharpness(small[0], small[1][:2]) == 0.0
