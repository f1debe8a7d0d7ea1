"""The registration's three-colour pass (register_kernels._blend_rows through _add5: each point's colour read once, a
corner's five sums at one offset of the flattened accumulator) adds exactly what its general loop adds: each colour splatted alone through the
general loop (one channel) gives, to the bit, that colour's sums, the weight sums and the depth sums of the
three-colour splat. Points overlap (several per pixel, at depths inside and outside the z-buffer's tolerance), fall
on the image's edges and outside it, and sit on whole pixel coordinates (zero bilinear weights)."""
from __future__ import annotations

import numpy as np

from platform_tools.dataset import register_kernels

H, W = 48, 64


def _points(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    uvz = np.empty((n, 3))
    uvz[:, 0] = rng.uniform(-0.999, W - 0.001, n)
    uvz[:, 1] = rng.uniform(-0.999, H - 0.001, n)
    uvz[: n // 10, :2] = np.round(uvz[: n // 10, :2])        # whole coordinates: three of four weights are 0
    uvz[:, 2] = rng.choice([1.0, 1.01, 1.5, 3.0], n) + rng.uniform(0, 0.005, n)
    return uvz, rng.permutation(n).astype(np.int64)


def _splat(uvz, idx, src, tol=0.02) -> np.ndarray:
    return splat(uvz, idx, src, H, W, tol)[1]


def splat(uvz, idx, src, h, w, tol) -> tuple[np.ndarray, np.ndarray]:
    """(z-buffer, sums (h, w, C + 2)) of both passes over points given in any order (register_kernels._zbuffer, then
    _blend_rows with every point in one row and a ring of the whole image, no row converted)."""
    zbuf = np.full((h, w), np.inf)
    register_kernels._zbuffer(uvz, len(idx), h, w, zbuf)
    ring = np.zeros((1 << (h - 1).bit_length(), w, src.shape[1] + 2))
    c = src.shape[1]
    register_kernels._blend_rows(uvz, idx, src, h, w, tol, zbuf, np.array([0, len(idx)]), np.zeros(1, np.int64), ring,
                                 0, 0.5, np.empty((1, 1, c), np.uint8), np.empty((1, 1), np.uint8),
                                 np.empty((1, 1), np.uint16))
    return zbuf, ring[:h]


def test_the_three_colour_pass_adds_what_the_general_loop_adds():
    uvz, idx = _points(30_000, 3)
    src = np.random.default_rng(4).integers(0, 256, (len(idx), 3), dtype=np.uint8)
    three = _splat(uvz, idx, src)
    assert (three[..., 3] > 0).mean() > 0.9 and three[..., 3].max() > 20 * three[..., 3][three[..., 3] > 0].min()
    for ch in range(3):
        one = _splat(uvz, idx, np.ascontiguousarray(src[:, ch:ch + 1]))
        assert np.array_equal(three[..., ch], one[..., 0])
        assert np.array_equal(three[..., 3], one[..., 1]) and np.array_equal(three[..., 4], one[..., 2])


def test_the_tolerance_keeps_the_far_surface_out_in_both_passes():
    """Two surfaces on the same pixels, 1.0 and 3.0 m: only the near one's colour is summed, in either pass."""
    uvz, idx = _points(4_000, 5)
    uvz[:, 2] = np.where(np.arange(len(idx)) % 2, 1.0, 3.0)
    src = np.empty((len(idx), 3), np.uint8)
    src[idx] = np.where(uvz[:, 2:] == 1.0, 200, 10)         # point j's colour is src[idx[j]]
    three = _splat(uvz, idx, src)
    one = _splat(uvz, idx, np.ascontiguousarray(src[:, :1]))
    near = uvz[:, 2] == 1.0
    reached = _splat(uvz[near], idx[near], src)[..., 3] > 0      # the pixels a near point's corners reach
    mean = three[..., 0] / np.where(three[..., 3] > 0, three[..., 3], 1)
    assert np.array_equal(three[..., 0], one[..., 0]) and np.array_equal(three[..., 4], one[..., 2])
    assert reached.mean() > 0.3 and (~reached & (three[..., 3] > 0)).mean() > 0.03    # both kinds of pixel exist
    assert np.allclose(mean[reached], 200.0, rtol=1e-12)        # the far surface never blends in
    assert np.allclose(mean[~reached & (three[..., 3] > 0)], 10.0, rtol=1e-12)
