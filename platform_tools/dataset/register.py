"""Register RGB into a thermal view from the ZED depth, as the paper: back-project every ZED left
pixel with its depth, transform it into the thermal camera with the extrinsics, project it with the
thermal model; a z-buffer keeps the nearest surface per thermal pixel and bilinear splatting spreads
each point over its four neighbouring pixels. Pixels without depth (NaN, inf, <= 0) are not splatted.

Two passes over the points (numba kernels in :mod:`.register_kernels`, one core; the points in view first gathered
into one (n, 3) array, and every thermal pixel's colour sums, weight and depth sum packed side by side beside the
z-buffer, so that pass 2 touches two cache lines per corner, not four arrays; for the export's 8-bit images those sums
live in a ring of thermal rows, each row converted as soon as no later point reaches it: :func:`ring_plan`):

1. project every point; each neighbouring pixel it would touch (bilinear weight > 0) keeps the
   nearest depth (the z-buffer);
2. a point adds ``weight x colour`` to a neighbour only when its depth is within
   ``zbuffer_tolerance_percent`` of that pixel's nearest: the same surface blends, an occluded
   surface never contributes, whatever the order of the points.

The output is the weighted mean per thermal pixel, a validity mask and the registered depth (Z in
the thermal optical frame). A pixel is valid when its total weight is at least ``min_coverage`` times
the weight a fully covered pixel receives (the ratio of ZED to thermal pixel density at the centre,
``fx fy`` over ``fx fy``): pixels on the rim of a surface, covered on one side only, would otherwise
carry a colour pulled up to a pixel away from where it belongs.

Known limit: the z-buffer's tolerance is relative to depth. Where a surface is seen at a grazing
angle and its depth changes by more than the tolerance across one thermal pixel (a floor far away at
low resolution), the far side of each pixel loses to the near side and the colour shifts toward the
near side by up to half a pixel. At the rig's resolutions (thermal 640x512) that starts beyond about
12 m of floor seen from 1.5 m. :func:`register_numpy` is the same
algorithm in plain numpy (``np.minimum.at`` / ``np.add.at``): the reference the bench and tests
compare with.

Lens models projected in numba: LENSMODEL_PINHOLE, LENSMODEL_STEREOGRAPHIC (the nominal Boson) and
LENSMODEL_OPENCV4/5/8 (what a calibration solves); any other mrcal model goes through
``mrcal.project`` (same result, slower).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from platform_tools.rig.cameras import imagersize

from .kernels import get

KIND_PINHOLE, KIND_STEREOGRAPHIC, KIND_OPENCV, KIND_MRCAL = 0, 1, 2, 3
_KINDS = {"LENSMODEL_PINHOLE": KIND_PINHOLE, "LENSMODEL_STEREOGRAPHIC": KIND_STEREOGRAPHIC,
          "LENSMODEL_OPENCV4": KIND_OPENCV, "LENSMODEL_OPENCV5": KIND_OPENCV, "LENSMODEL_OPENCV8": KIND_OPENCV}


def _padded(intrinsics: np.ndarray) -> np.ndarray:
    """Intrinsics (N,) zero-padded to at least the 12 entries the numba OpenCV projection reads."""
    k = np.zeros(max(12, len(intrinsics)))
    k[:len(intrinsics)] = intrinsics
    return k


@dataclass
class Result:
    image: np.ndarray       # (h, w, C) float32 weighted mean (0 where invalid)
    mask: np.ndarray        # (h, w) bool
    depth_m: np.ndarray     # (h, w) float32, NaN where invalid
    weight: np.ndarray      # (h, w) float32 total weight

    def image_u8(self) -> np.ndarray:
        return np.clip(np.rint(self.image), 0, 255).astype(np.uint8)


def zed_rays(zed) -> np.ndarray:
    """(H, W, 2) float64: (x/z, y/z) of every pixel's ray of a ZED model (``mrcal.cameramodel``)."""
    import mrcal
    lensmodel, k = zed.intrinsics()
    W, H = imagersize(zed)
    u, v = np.meshgrid(np.arange(W, dtype=float), np.arange(H, dtype=float))
    ray = mrcal.unproject(np.stack([u, v], -1), lensmodel, k)
    return np.ascontiguousarray(ray[..., :2] / ray[..., 2:3])


class Registrar:
    """RGB of one ZED left image size into one thermal camera. ``zed`` and ``thermal`` are
    ``mrcal.cameramodel``s already at the recorded sizes; ``rt_thermal_zed`` (6,) maps ZED left optical
    points into the thermal optical frame (metres)."""

    def __init__(self, zed, thermal, rt_thermal_zed: np.ndarray,
                 tolerance_percent: float, min_coverage: float = 0.5, rays: np.ndarray | None = None):
        """``rays``: :func:`zed_rays` of ``zed``, when the caller already has them (one ZED, two thermal views)."""
        import mrcal
        self.zed, self.thermal = zed, thermal
        zed_lensmodel, zed_k = zed.intrinsics()
        self.lensmodel, self.intrinsics = thermal.intrinsics()       # the thermal lens
        self.rays = zed_rays(zed) if rays is None else rays
        W, H = imagersize(zed)
        if self.rays.shape != (H, W, 2):
            raise ValueError(f"rays of shape {self.rays.shape} for a {W}x{H} ZED model")
        self.R = mrcal.R_from_r(rt_thermal_zed[:3])
        self.t = np.array(rt_thermal_zed[3:], float)
        self.kind = _KINDS.get(self.lensmodel, KIND_MRCAL)
        self.k = _padded(self.intrinsics)
        self.tol = tolerance_percent / 100.0
        #: weight a fully covered thermal pixel receives: ZED pixels per thermal pixel at the centre
        self.density = float(zed_k[0] * zed_k[1] / (self.intrinsics[0] * self.intrinsics[1]))
        self.min_weight = min_coverage * self.density
        self.out_w, self.out_h = imagersize(thermal)

    def _external_projection(self, depth: np.ndarray) -> np.ndarray:
        import mrcal
        p = np.concatenate([self.rays * depth[..., None], depth[..., None]], -1).reshape(-1, 3)
        p = p @ self.R.T + self.t
        with np.errstate(invalid="ignore"):
            return np.ascontiguousarray(mrcal.project(p, self.lensmodel, self.intrinsics))

    def points(self, depth: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(u, v, z) in the thermal image of every ZED pixel, flattened; NaN where there is none."""
        uvz, idx, n, _, _ = self._in_view(depth)
        out = np.full((3, depth.size), np.nan)
        out[:, idx[:n]] = uvz[:n].T
        return out[0], out[1], out[2]

    def _in_view(self, depth: np.ndarray) -> tuple[np.ndarray, np.ndarray, int, np.ndarray, np.ndarray]:
        """register_kernels._points_compact of a depth map: (uvz, idx, how many, row_start, row_reach)."""
        depth = np.ascontiguousarray(depth, np.float32)
        if depth.shape != self.rays.shape[:2]:
            raise ValueError(f"depth is {depth.shape[1]}x{depth.shape[0]}, the ZED model "
                             f"{self.rays.shape[1]}x{self.rays.shape[0]}")
        uvz, idx = np.empty((depth.size, 3), np.float64), np.empty(depth.size, np.int64)
        row_start, row_reach = np.empty(depth.shape[0] + 1, np.int64), np.empty((depth.shape[0], 2), np.int64)
        qext = self._external_projection(depth) if self.kind == KIND_MRCAL else np.zeros((1, 2))
        n = get("points_compact")(depth, self.rays, self.R, self.t, self.kind, self.k, qext, self.out_w, self.out_h,
                                  uvz, idx, row_start, row_reach)
        return uvz, idx, n, row_start, row_reach

    def _splat(self, depth: np.ndarray, src: np.ndarray, u8: bool):
        """Both passes of the splat of ``src`` (register_kernels._zbuffer, _blend_rows): with ``u8``, the export's
        images (image (h, w, C), mask, depth_mm, valid count) converted row by row from a ring of rows
        (:func:`ring_plan`); without, the sums of the whole image (h, w, C + 2)."""
        uvz, idx, n, row_start, row_reach = self._in_view(depth)
        flat = src.reshape(idx.shape[0], -1)
        h, w, C = self.out_h, self.out_w, flat.shape[1]
        zbuf = np.full((h, w), np.inf)
        get("zbuffer")(uvz, n, h, w, zbuf)
        if u8:
            final_below, rows = ring_plan(row_reach, h)
            image, mask, depth_mm = np.empty((h, w, C), np.uint8), np.empty((h, w), np.uint8), np.empty((h, w), np.uint16)
        else:
            final_below, rows = np.zeros(len(row_reach), np.int64), _pow2(h)
            image, mask, depth_mm = np.empty((1, 1, C), np.uint8), np.empty((1, 1), np.uint8), np.empty((1, 1), np.uint16)
        ring = np.zeros((rows, w, C + 2))
        valid = get("blend_rows")(uvz, idx, flat, h, w, self.tol, zbuf, row_start, final_below, ring, int(u8),
                                  self.min_weight, image, mask, depth_mm)
        return (image, mask, depth_mm, valid) if u8 else ring[:h]

    def _accumulate(self, depth: np.ndarray, src: np.ndarray):
        """(colour sums (h, w, C), weight sum, depth sum) of the splat."""
        packed = self._splat(depth, src, u8=False)
        C = packed.shape[2] - 2
        return packed[..., :C], packed[..., C], packed[..., C + 1]

    def register(self, depth: np.ndarray, src: np.ndarray) -> Result:
        """Splat `src` ((H, W) or (H, W, C), any dtype) into the thermal view."""
        return _finish(*self._accumulate(depth, src), self.min_weight)

    def register_u8(self, depth: np.ndarray, src: np.ndarray) -> "Images":
        """The export's images of :meth:`register` in one pass (numba): the same pixels as
        ``Result.image_u8()``, ``mask * 255`` and the depth in mm that the export writes."""
        image, mask, depth_mm, valid = self._splat(depth, src, u8=True)
        h, w, C = image.shape
        return Images(image if C > 1 else image[..., 0], mask, depth_mm, valid / (h * w))


def _pow2(n: int) -> int:
    """The smallest power of two at or above ``n`` (1 for 1 or less)."""
    return 1 << max(0, int(n) - 1).bit_length()


def ring_plan(row_reach: np.ndarray, out_h: int) -> tuple[np.ndarray, int]:
    """The ring of thermal rows of register_kernels._blend_rows, from ``row_reach`` (H, 2: the lowest and the highest
    thermal row each ZED row's points reach, register_kernels._points_compact): (final_below (H,): the thermal rows
    below final_below[r] are reached by no point of ZED row r or after, so they are final before row r; the ring's
    row count: the smallest power of two at or above the most rows open at once, from final_below[r] to the highest
    row reached by ZED rows 0..r, at most ``out_h``'s)."""
    lowest_after = np.minimum.accumulate(row_reach[::-1, 0])[::-1]
    highest_so_far = np.maximum.accumulate(row_reach[:, 1])
    open_rows = int((highest_so_far - lowest_after + 1).max(initial=1))
    return np.ascontiguousarray(np.clip(lowest_after, 0, out_h), np.int64), min(_pow2(open_rows), _pow2(out_h))


@dataclass
class Images:
    """What the export writes of one registration."""
    image: np.ndarray       # (h, w, C) uint8: the weighted mean rounded half to even, 0 where invalid
    mask: np.ndarray        # (h, w) uint8: 255 valid, 0 not
    depth_mm: np.ndarray    # (h, w) uint16: registered depth in mm, truncated, 0 where invalid
    fraction: float         # valid pixels / all pixels


def warm_up() -> None:
    """Load this module's kernels in this process (:mod:`.kernels`: the extension built ahead of time, or numba's
    from its disk cache, compiled the first time) by one :meth:`Registrar.register_u8` of a 4x3 depth map between two
    pinhole cameras: the same call, so the same argument types, as the export's (float32 depth, uint8 BGR, float64
    accumulators), and no other specialisation."""
    import mrcal
    cam = mrcal.cameramodel(intrinsics=("LENSMODEL_PINHOLE", np.array([2.0, 2.0, 1.5, 1.0])),
                            imagersize=np.array([4, 3]))
    Registrar(cam, cam, np.zeros(6), 2.0).register_u8(np.ones((3, 4), np.float32), np.zeros((3, 4, 3), np.uint8))


def _finish(acc, wsum, zacc, min_weight) -> Result:
    mask = wsum >= min_weight
    safe = np.where(mask, wsum, 1.0)
    image = np.where(mask[..., None], acc / safe[..., None], 0.0).astype(np.float32)
    depth = np.where(mask, zacc / safe, np.nan).astype(np.float32)
    return Result(image, mask, depth, wsum.astype(np.float32))


def register_numpy(reg: Registrar, depth: np.ndarray, src: np.ndarray) -> Result:
    """The same registration in plain numpy (np.minimum.at / np.add.at): the reference."""
    import mrcal
    depth = np.asarray(depth, np.float32)
    ok = np.isfinite(depth) & (depth > 0)
    d = depth[ok].astype(np.float64)
    p = np.stack([reg.rays[ok][:, 0] * d, reg.rays[ok][:, 1] * d, d], -1) @ reg.R.T + reg.t
    front = p[:, 2] > 0
    p = p[front]
    q = mrcal.project(p, reg.lensmodel, reg.intrinsics)
    u, v, z = q[:, 0], q[:, 1], p[:, 2]
    inside = (u > -1) & (u < reg.out_w) & (v > -1) & (v < reg.out_h)
    u, v, z = u[inside], v[inside], z[inside]
    colours = src.reshape(depth.size, -1)[ok.ravel()][front][inside].astype(np.float64)
    u0, v0 = np.floor(u).astype(np.int64), np.floor(v).astype(np.int64)
    fu, fv = u - u0, v - v0
    h, w = reg.out_h, reg.out_w
    zbuf = np.full(h * w, np.inf)
    nbrs = []
    for du, dv in ((0, 0), (1, 0), (0, 1), (1, 1)):
        uu, vv = u0 + du, v0 + dv
        wt = (fu if du else 1 - fu) * (fv if dv else 1 - fv)
        keep = (uu >= 0) & (uu < w) & (vv >= 0) & (vv < h) & (wt > 0)
        idx = (vv * w + uu)[keep]
        np.minimum.at(zbuf, idx, z[keep])
        nbrs.append((idx, wt[keep], keep))
    C = colours.shape[1]
    acc = np.zeros((h * w, C))
    wsum = np.zeros(h * w)
    zacc = np.zeros(h * w)
    for idx, wt, keep in nbrs:
        front = z[keep] <= zbuf[idx] * (1 + reg.tol)
        idx, wt = idx[front], wt[front]
        np.add.at(acc, idx, wt[:, None] * colours[keep][front])
        np.add.at(wsum, idx, wt)
        np.add.at(zacc, idx, wt * z[keep][front])
    return _finish(acc.reshape(h, w, C), wsum.reshape(h, w), zacc.reshape(h, w), reg.min_weight)
