"""The registration's numba kernels (:mod:`.register` holds what calls them): the projection of the ZED points into a
thermal view, the splat's two passes and the final pass to the export's 8-bit images. Imported only to compile them:
by numba's JIT on first use, or by the ahead-of-time build (:mod:`.kernels`), so that a process running the
export's samples from the built extension never imports numba.

Every kernel is compiled with numba's ``error_model="numpy"``: a division is the IEEE one (what numpy does), with no
test of its divisor for zero and no ZeroDivisionError to raise. The divisors here are positive where a result is
kept (a point's depth in front of the camera, a pixel's weight above ``min_coverage``'s), so the results are the same
to the bit (the bench's export outputs against b7c0534's; tests/dataset/test_dataset_register.py against plain
numpy); the projection of the points is 1.1x faster (30.9 -> 28.0 ms a view, best of 8, the bench's box scene).
"""
from __future__ import annotations

import numba
import numpy as np

from .register import KIND_MRCAL, KIND_PINHOLE, KIND_STEREOGRAPHIC


@numba.njit(cache=True, error_model="numpy", inline="always")
def _project(kind, k, x, y, z):
    if kind == KIND_PINHOLE:
        return k[0] * x / z + k[2], k[1] * y / z + k[3]
    if kind == KIND_STEREOGRAPHIC:
        s = 2.0 / (np.sqrt(x * x + y * y + z * z) + z)
        return k[0] * x * s + k[2], k[1] * y * s + k[3]
    # OpenCV: fx fy cx cy k1 k2 p1 p2 k3 k4 k5 k6
    xp = x / z
    yp = y / z
    r2 = xp * xp + yp * yp
    radial = (1.0 + r2 * (k[4] + r2 * (k[5] + r2 * k[8]))) / (1.0 + r2 * (k[9] + r2 * (k[10] + r2 * k[11])))
    xpp = xp * radial + 2.0 * k[6] * xp * yp + k[7] * (r2 + 2.0 * xp * xp)
    ypp = yp * radial + k[6] * (r2 + 2.0 * yp * yp) + 2.0 * k[7] * xp * yp
    return k[0] * xpp + k[2], k[1] * ypp + k[3]


@numba.njit(cache=True, error_model="numpy", inline="always")
def _corner(u0, v0, fu, fv, corner):
    """Pixel (column, row) and bilinear weight of neighbour ``corner`` (0..3: du = corner & 1, dv = corner >> 1)
    of a point at (u0 + fu, v0 + fv), u0 and v0 whole, fu and fv in [0, 1)."""
    du = corner & 1
    dv = corner >> 1
    return u0 + du, v0 + dv, (fv if dv else 1.0 - fv) * (fu if du else 1.0 - fu)


@numba.njit(cache=True, error_model="numpy", inline="always")
def _inside(u0, v0, out_w, out_h):
    """Whether all four neighbours of a point at (u0 + fu, v0 + fv) lie inside an ``out_w`` x ``out_h`` image."""
    return 0 <= u0 and u0 + 1 < out_w and 0 <= v0 and v0 + 1 < out_h


@numba.njit(cache=True, error_model="numpy", inline="always")
def _weights(fu, fv):
    """The bilinear weights of the four neighbours in :func:`_corner`'s order, as the same products."""
    return (1.0 - fv) * (1.0 - fu), (1.0 - fv) * fu, fv * (1.0 - fu), fv * fu


@numba.njit(cache=True, error_model="numpy")
def _points_compact(depth, rays, R, t, kind, k, qext, out_w, out_h, uvz, idx):
    """Thermal pixel coordinates and depth of the ZED pixels in view (with depth, in front, projecting inside), in
    pixel order: ``uvz[j]`` (u, v, z) of ZED pixel ``idx[j]`` (flattened); returns how many."""
    H, W = depth.shape
    n = 0
    for r in range(H):
        for c in range(W):
            i = r * W + c
            d = depth[r, c]
            if not (d > 0.0 and d < np.inf):
                continue
            X = rays[r, c, 0] * d
            Y = rays[r, c, 1] * d
            x = R[0, 0] * X + R[0, 1] * Y + R[0, 2] * d + t[0]
            y = R[1, 0] * X + R[1, 1] * Y + R[1, 2] * d + t[1]
            z = R[2, 0] * X + R[2, 1] * Y + R[2, 2] * d + t[2]
            if z <= 0.0:
                continue
            if kind == KIND_MRCAL:
                u = qext[i, 0]
                v = qext[i, 1]
            else:
                u, v = _project(kind, k, x, y, z)
            if not (u > -1.0 and u < out_w and v > -1.0 and v < out_h):
                continue
            uvz[n, 0] = u
            uvz[n, 1] = v
            uvz[n, 2] = z
            idx[n] = i
            n += 1
    return n


@numba.njit(cache=True, error_model="numpy")
def _splat_packed(uvz, idx, n, src, out_h, out_w, tol, zbuf, packed):
    """The two passes over the ``n`` points in view: pass 0 into the z-buffer ``zbuf`` (h, w; +inf on entry), pass 1
    into ``packed`` (h, w, C + 2; 0 on entry, C-contiguous): the C colour sums, the weight sum, the weighted depth
    sum of each pixel side by side. The same additions in the same order as three separate arrays: the same sums to
    the bit. Three colours (the export's BGR) go through :func:`_blend3`. A point whose four neighbours are all inside
    (all but the image's rim) takes them without a bounds test, and the z-buffer keeps the nearer depth with a
    ``min`` instead of a branch on the comparison (unpredictable where surfaces meet): the same result, the splat
    1.15 to 1.25 times faster on the export's images (docs/dataset.md "Speed")."""
    C = src.shape[1]
    zflat = zbuf.reshape(out_h * out_w)
    for j in range(n):                      # pass 0: the z-buffer
        u = uvz[j, 0]
        v = uvz[j, 1]
        z = uvz[j, 2]
        u0 = int(np.floor(u))
        v0 = int(np.floor(v))
        fu = u - u0
        fv = v - v0
        if _inside(u0, v0, out_w, out_h):
            q = v0 * out_w + u0
            w0, w1, w2, w3 = _weights(fu, fv)
            if w0 > 0.0:
                zflat[q] = min(zflat[q], z)
            if w1 > 0.0:
                zflat[q + 1] = min(zflat[q + 1], z)
            if w2 > 0.0:
                zflat[q + out_w] = min(zflat[q + out_w], z)
            if w3 > 0.0:
                zflat[q + out_w + 1] = min(zflat[q + out_w + 1], z)
            continue
        for corner in range(4):             # on the image's rim
            uu, vv, w = _corner(u0, v0, fu, fv, corner)
            if 0 <= vv < out_h and 0 <= uu < out_w and w > 0.0 and z < zflat[vv * out_w + uu]:
                zflat[vv * out_w + uu] = z
    if C == 3:
        _blend3(uvz, idx, n, src, out_h, out_w, tol, zbuf, packed.reshape(out_h * out_w * 5))
        return
    for j in range(n):                      # pass 1: the surface nearest each pixel blends
        u = uvz[j, 0]
        v = uvz[j, 1]
        z = uvz[j, 2]
        u0 = int(np.floor(u))
        v0 = int(np.floor(v))
        i = idx[j]
        for corner in range(4):
            uu, vv, w = _corner(u0, v0, u - u0, v - v0, corner)
            if 0 <= vv < out_h and 0 <= uu < out_w and w > 0.0 and z <= zbuf[vv, uu] * (1.0 + tol):
                for ch in range(C):
                    packed[vv, uu, ch] += w * src[i, ch]
                packed[vv, uu, C] += w
                packed[vv, uu, C + 1] += w * z


@numba.njit(cache=True, error_model="numpy", inline="always")
def _blend3(uvz, idx, n, src, out_h, out_w, tol, zbuf, flat):
    """Pass 1 of :func:`_splat_packed` for three colours, into its accumulator flattened (``flat``: h * w * 5): each
    point's colour read once, a corner's five sums at one computed offset. The same products and additions in the
    same order as the general loop (the whole splat 1.2 to 1.25 times faster, docs/dataset.md "Speed")."""
    row = out_w * 5
    for j in range(n):
        u = uvz[j, 0]
        v = uvz[j, 1]
        z = uvz[j, 2]
        u0 = int(np.floor(u))
        v0 = int(np.floor(v))
        fu = u - u0
        fv = v - v0
        i = idx[j]
        b = np.float64(src[i, 0])
        g = np.float64(src[i, 1])
        r = np.float64(src[i, 2])
        if _inside(u0, v0, out_w, out_h):
            p = (v0 * out_w + u0) * 5
            w0, w1, w2, w3 = _weights(fu, fv)
            _add5(flat, p, w0, z, zbuf[v0, u0] * (1.0 + tol), b, g, r)
            _add5(flat, p + 5, w1, z, zbuf[v0, u0 + 1] * (1.0 + tol), b, g, r)
            _add5(flat, p + row, w2, z, zbuf[v0 + 1, u0] * (1.0 + tol), b, g, r)
            _add5(flat, p + row + 5, w3, z, zbuf[v0 + 1, u0 + 1] * (1.0 + tol), b, g, r)
            continue
        for corner in range(4):             # on the image's rim
            uu, vv, w = _corner(u0, v0, fu, fv, corner)
            if 0 <= vv < out_h and 0 <= uu < out_w:
                _add5(flat, vv * row + uu * 5, w, z, zbuf[vv, uu] * (1.0 + tol), b, g, r)


@numba.njit(cache=True, error_model="numpy", inline="always")
def _add5(flat, p, w, z, zmax, b, g, r):
    """One corner of :func:`_blend3`: the five sums at ``flat[p:p + 5]`` when the weight is positive and the point
    is on the nearest surface (``z <= zmax``)."""
    if w > 0.0 and z <= zmax:
        flat[p] += w * b
        flat[p + 1] += w * g
        flat[p + 2] += w * r
        flat[p + 3] += w
        flat[p + 4] += w * z


@numba.njit(cache=True, error_model="numpy")
def _finish_u8(packed, min_weight, image, mask, depth_mm):
    """:func:`_finish` then the export's conversions, per pixel with the same float32 steps, from the packed
    accumulator (:func:`_splat_packed`); returns the count of valid pixels."""
    h, w, C = packed.shape[0], packed.shape[1], packed.shape[2] - 2
    n = 0
    for r in range(h):
        for c in range(w):
            ws = packed[r, c, C]
            if ws >= min_weight:
                n += 1
                mask[r, c] = 255
                for ch in range(C):
                    v = np.rint(np.float32(packed[r, c, ch] / ws))
                    image[r, c, ch] = 0 if v < 0 else (255 if v > 255 else np.uint8(v))
                d = np.float32(packed[r, c, C + 1] / ws) * np.float32(1000.0)
                if not (d > 0):      # NaN or not positive
                    depth_mm[r, c] = 0
                elif d > 65535:
                    depth_mm[r, c] = 65535
                else:
                    depth_mm[r, c] = np.uint16(d)
            else:
                mask[r, c] = 0
                depth_mm[r, c] = 0
                for ch in range(C):
                    image[r, c, ch] = 0
    return n
