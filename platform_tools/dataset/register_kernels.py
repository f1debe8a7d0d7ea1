"""The registration's numba kernels (:mod:`.register` holds what calls them): the projection of the ZED points into a
thermal view (:func:`_points_compact`), the splat's pass 0 into the z-buffer (:func:`_zbuffer`) and its pass 1 with
the final conversion to the export's 8-bit images (:func:`_blend_rows`). Imported only to compile them: by numba's
JIT on first use, or by the ahead-of-time build (:mod:`.kernels`), so that a process running the export's samples
from the built extension never imports numba.

Pass 1 accumulates into a ring of thermal rows, not into a whole image: the points come in the ZED's row order, and
the points of one ZED row reach a band of thermal rows (39 of 512 for the rig's left Boson). Once no later point can
reach a thermal row, that row's sums are final: it is converted to its output pixels and its ring row zeroed for the
row that takes its place. The sums are the whole-image accumulator's (the same additions in the same order), but a
ring of 64 rows (1.6 MB at 640 px) stays in a core's cache where the whole accumulator (13 MB) went to memory three
times (zeroed, summed into, read); the registration became 1.1-1.2 times faster under an export's load
(docs/dataset.md "Speed").

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
def _point(uvz, j):
    """Point ``j`` of ``uvz`` (u, v, z) as the splat takes it: (u0, v0, fu, fv, z), its pixel (column, row) and its
    fractions there (u = u0 + fu, v = v0 + fv, fu and fv in [0, 1))."""
    u = uvz[j, 0]
    v = uvz[j, 1]
    u0 = int(np.floor(u))
    v0 = int(np.floor(v))
    return u0, v0, u - u0, v - v0, uvz[j, 2]


@numba.njit(cache=True, error_model="numpy", inline="always")
def _inside(u0, v0, out_w, out_h):
    """Whether all four neighbours of a point at (u0 + fu, v0 + fv) lie inside an ``out_w`` x ``out_h`` image."""
    return 0 <= u0 and u0 + 1 < out_w and 0 <= v0 and v0 + 1 < out_h


@numba.njit(cache=True, error_model="numpy", inline="always")
def _weights(fu, fv):
    """The bilinear weights of the four neighbours in :func:`_corner`'s order, as the same products."""
    return (1.0 - fv) * (1.0 - fu), (1.0 - fv) * fu, fv * (1.0 - fu), fv * fu


@numba.njit(cache=True, error_model="numpy")
def _points_compact(depth, rays, R, t, kind, k, qext, out_w, out_h, uvz, idx, row_start, row_reach):
    """Thermal pixel coordinates and depth of the ZED pixels in view (with depth, in front, projecting inside), in
    pixel order: ``uvz[j]`` (u, v, z) of ZED pixel ``idx[j]`` (flattened); returns how many. Per ZED row r: its points
    are ``uvz[row_start[r]:row_start[r + 1]]`` (``row_start``: H + 1), and ``row_reach[r]`` (H, 2) the lowest and the
    highest thermal row their bilinear corners reach, ``floor(v)`` and ``floor(v) + 1`` (``out_h`` and -1 for a row
    without points)."""
    H, W = depth.shape
    n = 0
    for r in range(H):
        row_start[r] = n
        lo = out_h
        hi = -1
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
            v0 = int(np.floor(v))
            lo = min(lo, v0)
            hi = max(hi, v0 + 1)
        row_reach[r, 0] = lo
        row_reach[r, 1] = hi
    row_start[H] = n
    return n


@numba.njit(cache=True, error_model="numpy")
def _zbuffer(uvz, n, out_h, out_w, zbuf):
    """Pass 0 of the splat over the ``n`` points in view: each neighbouring pixel a point touches (bilinear weight
    > 0) keeps the nearest depth in ``zbuf`` (h, w; +inf on entry). A point whose four neighbours are all inside (all
    but the image's rim) takes them without a bounds test, and keeps the nearer depth with a ``min`` instead of a
    branch on the comparison (unpredictable where surfaces meet; 1.15-1.25x on an AMD Zen 1, the same on the Intel
    Xeon of the eighth round: 3.19 against 3.26 ms a view with a branch)."""
    zflat = zbuf.reshape(out_h * out_w)
    for j in range(n):
        u0, v0, fu, fv, z = _point(uvz, j)
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


@numba.njit(cache=True, error_model="numpy")
def _blend_rows(uvz, idx, src, out_h, out_w, tol, zbuf, row_start, final_below, ring, finish, min_weight,
                image, mask, depth_mm):
    """Pass 1 of the splat, after :func:`_zbuffer`: the points of each ZED row in turn (``row_start``, from
    :func:`_points_compact`) add, where they are on the nearest surface, into ``ring`` (R, w, C + 2; zeros on entry,
    R a power of two): thermal row v's C colour sums, weight sum and weighted depth sum side by side in ring row
    ``v % R``. With ``finish`` (1), before the points of ZED row r every thermal row below ``final_below[r]`` (no point
    of row r or after reaches it) is converted by :func:`_finish_row` into ``image``, ``mask`` and ``depth_mm`` and
    its ring row zeroed, and the rows left are converted at the end; returns the count of valid pixels. R must hold
    every row open at once (:func:`.register.ring_plan`). With ``finish`` 0 nothing is converted (R >= h: ``ring``
    holds the whole image's sums, for the float path) and 0 is returned.

    Each point's colour is read once and a corner's sums are added at one computed offset; three colours (the
    export's BGR) go through :func:`_add5`. The same products and additions in the same order as a whole-image
    accumulator: the same sums to the bit."""
    H = row_start.shape[0] - 1
    C = src.shape[1]
    S = C + 2
    m = ring.shape[0] - 1
    row = out_w * S
    flat = ring.reshape(ring.shape[0] * row)
    done = 0
    valid = 0
    for r in range(H):
        if finish:
            while done < final_below[r]:
                valid += _finish_row(flat, (done & m) * row, done, out_w, C, min_weight, image, mask, depth_mm)
                done += 1
        for j in range(row_start[r], row_start[r + 1]):
            u0, v0, fu, fv, z = _point(uvz, j)
            i = idx[j]
            if C == 3:
                b = np.float64(src[i, 0])
                g = np.float64(src[i, 1])
                rr = np.float64(src[i, 2])
                if _inside(u0, v0, out_w, out_h):
                    p0 = (v0 & m) * row + u0 * S
                    p1 = ((v0 + 1) & m) * row + u0 * S
                    w0, w1, w2, w3 = _weights(fu, fv)
                    _add5(flat, p0, w0, z, zbuf[v0, u0] * (1.0 + tol), b, g, rr)
                    _add5(flat, p0 + S, w1, z, zbuf[v0, u0 + 1] * (1.0 + tol), b, g, rr)
                    _add5(flat, p1, w2, z, zbuf[v0 + 1, u0] * (1.0 + tol), b, g, rr)
                    _add5(flat, p1 + S, w3, z, zbuf[v0 + 1, u0 + 1] * (1.0 + tol), b, g, rr)
                    continue
                for corner in range(4):             # on the image's rim
                    uu, vv, w = _corner(u0, v0, fu, fv, corner)
                    if 0 <= vv < out_h and 0 <= uu < out_w:
                        _add5(flat, (vv & m) * row + uu * S, w, z, zbuf[vv, uu] * (1.0 + tol), b, g, rr)
                continue
            for corner in range(4):                 # any other number of colours
                uu, vv, w = _corner(u0, v0, fu, fv, corner)
                if 0 <= vv < out_h and 0 <= uu < out_w and w > 0.0 and z <= zbuf[vv, uu] * (1.0 + tol):
                    p = (vv & m) * row + uu * S
                    for ch in range(C):
                        flat[p + ch] += w * src[i, ch]
                    flat[p + C] += w
                    flat[p + C + 1] += w * z
    if finish:
        while done < out_h:
            valid += _finish_row(flat, (done & m) * row, done, out_w, C, min_weight, image, mask, depth_mm)
            done += 1
    return valid


@numba.njit(cache=True, error_model="numpy", inline="always")
def _add5(flat, p, w, z, zmax, b, g, r):
    """One corner of a three-colour point in :func:`_blend_rows`: the five sums at ``flat[p:p + 5]`` when the weight
    is positive and the point is on the nearest surface (``z <= zmax``)."""
    if w > 0.0 and z <= zmax:
        flat[p] += w * b
        flat[p + 1] += w * g
        flat[p + 2] += w * r
        flat[p + 3] += w
        flat[p + 4] += w * z


@numba.njit(cache=True, error_model="numpy", inline="always")
def _finish_row(flat, base, v, out_w, C, min_weight, image, mask, depth_mm):
    """Thermal row ``v`` from its sums at ``flat[base:base + out_w * (C + 2)]``: the weighted mean colour, mask and
    depth, with the float32 steps of register._finish and the export's conversions (rounded half to even and clipped
    to uint8; 255 / 0; millimetres truncated and clipped to uint16, 0 where invalid); then those sums zeroed.
    Returns the row's count of valid pixels."""
    S = C + 2
    n = 0
    for c in range(out_w):
        p = base + c * S
        ws = flat[p + C]
        if ws >= min_weight:
            n += 1
            mask[v, c] = 255
            for ch in range(C):
                x = np.rint(np.float32(flat[p + ch] / ws))
                image[v, c, ch] = 0 if x < 0 else (255 if x > 255 else np.uint8(x))
            d = np.float32(flat[p + C + 1] / ws) * np.float32(1000.0)
            if not (d > 0):      # NaN or not positive
                depth_mm[v, c] = 0
            elif d > 65535:
                depth_mm[v, c] = 65535
            else:
                depth_mm[v, c] = np.uint16(d)
        else:
            mask[v, c] = 0
            depth_mm[v, c] = 0
            for ch in range(C):
                image[v, c, ch] = 0
    for q in range(base, base + out_w * S):
        flat[q] = 0.0
    return n
