"""numba kernels for the detector's per-candidate and per-corner loops (one core, cache=True so the
compile happens once per machine, not per image or per process).

Each kernel does exactly what the numpy/Python code it replaced did, in the same order (the ring
test's means are summed the way numpy sums a row of 32, so its sign tests see the same numbers);
tests/calibration/test_detect.py checks them against plain reference versions.
"""
from __future__ import annotations

import math

import numba
import numpy as np

TWO_PI = 2.0 * np.pi


@numba.njit(cache=True, inline="always")
def _rowsum32(v):
    """numpy's pairwise sum of a row (8 accumulators for 8 <= n <= 128), bit for bit."""
    n = v.shape[0]
    if n < 8:
        s = 0.0
        for k in range(n):
            s += v[k]
        return s
    r0, r1, r2, r3, r4, r5, r6, r7 = v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7]
    m = n - n % 8
    for i in range(8, m, 8):
        r0 += v[i]
        r1 += v[i + 1]
        r2 += v[i + 2]
        r3 += v[i + 3]
        r4 += v[i + 4]
        r5 += v[i + 5]
        r6 += v[i + 6]
        r7 += v[i + 7]
    s = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    for i in range(m, n):
        s += v[i]
    return s


@numba.njit(cache=True)
def ring_kernel(samples, inside, ok, dirs, strength, sign):
    """The ring test of candidates.ring_check on sampled rings ``samples`` (n, N) float32; fills
    ok, dirs, strength, sign (rows with four sign changes get dirs/strength/sign, as before)."""
    n, N = samples.shape
    v = np.empty(N)
    av = np.empty(N)
    ch = np.zeros(N, np.bool_)
    idx = np.empty(4, np.int64)
    theta = np.empty(4)
    sums = np.empty(4)
    cnts = np.empty(4)
    step = TWO_PI / N
    lo_seg = np.pi / 5
    hi_seg = np.pi - np.pi / 5
    for r in range(n):
        if not inside[r]:
            continue
        for k in range(N):
            v[k] = np.float64(samples[r, k])
        mean = _rowsum32(v) / N
        for k in range(N):
            v[k] = v[k] - mean
        nc = 0
        for k in range(N):
            k1 = k + 1 if k + 1 < N else 0
            c = (v[k] > 0) != (v[k1] > 0)
            ch[k] = c
            if c:
                if nc < 4:
                    idx[nc] = k
                nc += 1
        if nc != 4:
            continue
        for m in range(4):
            a = v[idx[m]]
            k1 = idx[m] + 1 if idx[m] + 1 < N else 0
            b = v[k1]
            theta[m] = (idx[m] + a / (a - b)) * step
        smin = 1e300
        smax = -1e300
        for m in range(4):
            s = (theta[m + 1] if m < 3 else theta[0] + TWO_PI) - theta[m]
            smin = min(smin, s)
            smax = max(smax, s)
        good = (smin >= lo_seg) and (smax <= hi_seg)
        good = good and (abs(theta[2] - theta[0] - np.pi) <= 0.45) and (abs(theta[3] - theta[1] - np.pi) <= 0.45)
        vmax = v[0]
        vmin = v[0]
        for k in range(N):
            vmax = max(vmax, v[k])
            vmin = min(vmin, v[k])
        amp = 0.5 * (vmax - vmin)
        for m in range(4):
            sums[m] = 0.0
            cnts[m] = 0.0
        sec = 1 if ch[N - 1] else 0
        for k in range(N):
            if k > 0 and ch[k - 1]:
                sec += 1
            sid = sec % 4
            sums[sid] += v[k]
            cnts[sid] += 1.0
        mmin = 1e300
        for m in range(4):
            mmin = min(mmin, abs(sums[m]) / max(cnts[m], 1.0))
        good = good and mmin >= 0.35 * amp
        sg0, sg1, sg2, sg3 = np.sign(sums[0]), np.sign(sums[1]), np.sign(sums[2]), np.sign(sums[3])
        good = good and (sg0 == sg2) and (sg1 == sg3) and (sg0 != sg1)
        x1 = math.cos(theta[0]) - math.cos(theta[2])
        y1 = math.sin(theta[0]) - math.sin(theta[2])
        x2 = math.cos(theta[1]) - math.cos(theta[3])
        y2 = math.sin(theta[1]) - math.sin(theta[3])
        ok[r] = good
        dirs[r, 0] = math.atan2(y1, x1) % np.pi
        dirs[r, 1] = math.atan2(y2, x2) % np.pi
        for k in range(N):
            av[k] = abs(v[k])
        strength[r] = _rowsum32(av) / N
        sign[r] = sg1


@numba.njit(cache=True, inline="always")
def _adiff(a, b):
    d = abs((a - b) % np.pi)
    return min(d, np.pi - d)


@numba.njit(cache=True)
def link_kernel(xy, dirs, dist, nb, angle_tol, agree_tol, spacing_ratio):
    """grid.link's slot choice, mutual check and spacing check (same order, same ties)."""
    n = xy.shape[0]
    k = nb.shape[1]
    slots = -np.ones((n, 2, 2), np.int64)
    best = np.full((n, 2, 2), np.inf)
    for col in range(1, k):
        for p in range(n):
            q = nb[p, col]
            dx = xy[q, 0] - xy[p, 0]
            dy = xy[q, 1] - xy[p, 1]
            phi = math.atan2(dy, dx)
            for L in range(2):
                th = dirs[p, L]
                if not (_adiff(phi, th) < angle_tol):
                    continue
                if not (min(_adiff(dirs[q, 0], th), _adiff(dirs[q, 1], th)) < agree_tol):
                    continue
                s = 1 if math.cos(phi - th) < 0 else 0
                if dist[p, col] < best[p, L, s]:
                    best[p, L, s] = dist[p, col]
                    slots[p, L, s] = q
    # mutual choice (in place, in order, as the Python loop did)
    for p in range(n):
        for L in range(2):
            for s in range(2):
                q = slots[p, L, s]
                if q >= 0:
                    back = False
                    for a in range(2):
                        for b in range(2):
                            if slots[q, a, b] == p:
                                back = True
                    if not back:
                        slots[p, L, s] = -1
    # spacing consistency along a line, lengths measured after the mutual check
    length = np.full((n, 2, 2), np.nan)
    for p in range(n):
        for L in range(2):
            for s in range(2):
                q = slots[p, L, s]
                if q >= 0:
                    length[p, L, s] = math.sqrt((xy[q, 0] - xy[p, 0]) ** 2 + (xy[q, 1] - xy[p, 1]) ** 2)
    for p in range(n):
        for L in range(2):
            a = length[p, L, 0]
            b = length[p, L, 1]
            if np.isfinite(a) and np.isfinite(b) and max(a, b) > spacing_ratio * min(a, b):
                s = 0 if a > b else 1
                q = slots[p, L, s]
                slots[p, L, s] = -1
                if q >= 0:
                    for a2 in range(2):
                        for b2 in range(2):
                            if slots[q, a2, b2] == p:
                                slots[q, a2, b2] = -1
    return slots
