"""X-corner candidates: saddle points of the smoothed image, checked by sampling a ring around each.

A chessboard corner is a saddle of the (blurred) image: the Hessian determinant is negative there,
so ``S = Ixy^2 - Ixx Iyy`` peaks. Local maxima of S are only candidates: clutter corners, noise and
edges also make saddles. A ring of samples around a true X-corner changes sign exactly four times,
with opposite sectors of equal sign and the two lines through the corner nearly straight; the
crossing angles give the two edge directions the grid builder follows.
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from ._fast import ring_kernel
from .refine import image_noise

RING_SAMPLES = 32
MAX_CANDIDATES = 3000
NOISE_FLOOR = 4.0        # local std below this many times the image noise is not stretched


@dataclass(frozen=True)
class Candidates:
    xy: np.ndarray          # (n, 2) pixel positions
    dirs: np.ndarray        # (n, 2) angles (radians) of the two edge lines, each mod pi
    strength: np.ndarray    # (n,) ring contrast, in units of the normalised image
    sign: np.ndarray        # (n,) sign of the sector between dirs[0] and dirs[1] (going from 0 to 1)


DESTRIPE_WINDOW = 33     # columns
DESTRIPE_ROW_STEP = 4    # rows sampled for the median (every 2nd: no better, twice the time; 8th: noisier)
DESTRIPE_BANDS = 8       # horizontal bands of rows, each with its own column estimate ...
DESTRIPE_AGREE = 2.0     # ... agreeing within this many times the pixel noise (vertical second differences)
DESTRIPE_SUPPORT = 0.375   # the share of the bands that must agree for a column's pattern to count as measured


def column_pattern(f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(W,) the column fixed pattern of ``f``, and (W,) whether the rows agree on it. Per column, the
    median over rows of what a horizontal smoothing takes away. A column pattern is the same in every
    row, so the rows are also taken in DESTRIPE_BANDS bands: the column's value counts as measured
    where at least DESTRIPE_SUPPORT of the bands' medians agree with the whole median (within
    DESTRIPE_AGREE x the pixel noise); where they do not, what the median sees is the scene's own
    vertical edges. (A board filling the image: every row of a column near a vertical edge of its
    squares holds that edge's ramp, of one sign or the other by the square's row, and the median
    lands on one of them: a 56 x 44 board of 12 mm squares at 0.14 m through the Kannala-Brandt truth
    lens had its corners moved 0.60 px RMS by the destriping, 48 over 1 px, on a noise-free image.)"""
    # the smoothing must be wide: what it keeps of the pattern stays in the image, the same in every
    # image of a set, and shifts corners the same way every time, which biases the lens
    # (bench/bench_corner_bias.py, "+ column pattern"). A 9-column window left a third of the
    # pattern's std (hard 10x7 seed 200 corner RMS 0.163 px, 7x7 seed 300 0.205 px); 33 columns over
    # every 4th row: 0.11 / 0.14 px. Wider lets the scene's own vertical edges in (65: worse again).
    hp = f - cv2.blur(f, (DESTRIPE_WINDOW, 1), borderType=cv2.BORDER_REFLECT)
    rows = hp[::DESTRIPE_ROW_STEP]
    whole = np.median(rows, axis=0)
    n_bands = max(1, min(DESTRIPE_BANDS, len(rows) // 4))
    m = np.stack([np.median(b, axis=0) for b in np.array_split(rows, n_bands, axis=0)])   # (bands, W)
    # the pixel noise from vertical second differences (a column pattern has none)
    a, b, c = f[0:-2:4], f[1:-1:4], f[2::4]
    n = min(len(a), len(b), len(c))
    d = (a[:n] - 2 * b[:n] + c[:n]).ravel()
    noise = float(1.4826 * np.median(np.abs(d - np.median(d)))) / np.sqrt(6.0) if d.size else 0.0
    support = np.sum(np.abs(m - whole[None, :]) <= DESTRIPE_AGREE * max(noise, 1e-6), axis=0)
    return whole.astype(np.float32), support >= DESTRIPE_SUPPORT * n_bands


def normalise(img: np.ndarray, measured_only: bool = False) -> np.ndarray:
    """Float image with the column fixed pattern removed (column_pattern); ``measured_only``: only in
    the columns where the rows agree on it (the image the sub-pixel fits run on: a column pattern
    left in is noise, a board's edges taken for one move its corners)."""
    f = img.astype(np.float32)
    pattern, measured = column_pattern(f)
    return f - (np.where(measured, pattern, 0.0) if measured_only else pattern)[None, :]


def sample(g: np.ndarray, px: np.ndarray, py: np.ndarray) -> np.ndarray:
    """Bilinear samples of ``g`` at (px, py) (any equal shapes, fewer than 32767 rows), edge pixels
    repeated outside."""
    shape = px.shape
    mx = np.ascontiguousarray(px.reshape(shape[0], -1), dtype=np.float32)
    my = np.ascontiguousarray(py.reshape(shape[0], -1), dtype=np.float32)
    return cv2.remap(g, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE).reshape(shape)


def _smooth(f: np.ndarray, size: int) -> np.ndarray:
    """Two box filters: a cheap, constant-time stand-in for a wide Gaussian."""
    return cv2.blur(cv2.blur(f, (size, size)), (size, size))


def local_contrast(f: np.ndarray, size: int = 21) -> tuple[np.ndarray, np.ndarray]:
    """Local mean and standard deviation over a window of about ``size`` pixels."""
    mu = _smooth(f, size)
    var = _smooth((f - mu) ** 2, size)
    return mu, np.sqrt(np.maximum(var, 1e-12))


def saddle_response(g: np.ndarray) -> np.ndarray:
    ixx = cv2.Sobel(g, cv2.CV_32F, 2, 0, ksize=3)
    iyy = cv2.Sobel(g, cv2.CV_32F, 0, 2, ksize=3)
    ixy = cv2.Sobel(g, cv2.CV_32F, 1, 1, ksize=3)
    return ixy * ixy - ixx * iyy


def local_maxima(S: np.ndarray, threshold: float, radius: int = 2) -> np.ndarray:
    k = 2 * radius + 1
    dil = cv2.dilate(S, np.ones((k, k), np.uint8))
    ys, xs = np.nonzero((S >= dil) & (S > threshold))
    if len(xs) > MAX_CANDIDATES:
        keep = np.argsort(S[ys, xs])[::-1][:MAX_CANDIDATES]
        ys, xs = ys[keep], xs[keep]
    return np.stack([xs, ys], axis=1).astype(np.float64)


def ring_check(g: np.ndarray, xy: np.ndarray, radius) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Ring test at ``radius`` (a number, or one per point): (ok, dirs (n,2), strength, sign) for
    each point. The rings are sampled by cv2.remap, the tests run in numba (_fast.ring_kernel);
    ``_ring_check_numpy`` is the same test in numpy (the reference the tests compare with)."""
    ok, dirs, strength, sign = _ring_outputs(len(xy))
    if len(xy) == 0:
        return ok, dirs, strength, sign
    vals, inside = _ring_samples(g, xy, radius)
    ring_kernel(np.ascontiguousarray(vals, dtype=np.float32), inside, ok, dirs, strength, sign)
    return ok, dirs, strength, sign


def _ring_outputs(n: int):
    """Empty results of the ring test for ``n`` points: ok, dirs, strength, sign."""
    return np.zeros(n, bool), np.zeros((n, 2)), np.zeros(n), np.zeros(n)


def _ring_samples(g: np.ndarray, xy: np.ndarray, radius):
    """Image values on a ring of RING_SAMPLES points around each point (cv2.remap), and whether the
    whole ring lies inside the image."""
    n = len(xy)
    ang = np.arange(RING_SAMPLES) * (2 * np.pi / RING_SAMPLES)
    r = np.broadcast_to(np.asarray(radius, float), (n,))[:, None]
    px = xy[:, 0:1] + r * np.cos(ang)[None, :]
    py = xy[:, 1:2] + r * np.sin(ang)[None, :]
    H, W = g.shape
    inside = (px.min(1) >= 0) & (py.min(1) >= 0) & (px.max(1) <= W - 1) & (py.max(1) <= H - 1)
    return sample(g, px, py), inside


def _ring_check_numpy(g: np.ndarray, xy: np.ndarray, radius) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """ring_check in plain numpy (vectorised): the reference for _fast.ring_kernel."""
    n = len(xy)
    N = RING_SAMPLES
    ok, dirs, strength, sign = _ring_outputs(n)
    if n == 0:
        return ok, dirs, strength, sign
    vals, inside = _ring_samples(g, xy, radius)
    vals = vals.astype(np.float64)
    # the level between the sectors: the mean of a ring around an X-corner (cheaper than the
    # median and as good for the sign pattern; the checks below reject what it does not fit)
    vals = vals - vals.mean(axis=1, keepdims=True)
    pos = vals > 0
    change = pos != np.roll(pos, -1, axis=1)          # sign change between sample k and k+1
    four = inside & (change.sum(1) == 4)
    rows = np.flatnonzero(four)
    if len(rows) == 0:
        return ok, dirs, strength, sign
    v = vals[rows]
    idx = np.nonzero(change[rows])[1].reshape(-1, 4)   # sorted per row
    a = np.take_along_axis(v, idx, 1)
    b = np.take_along_axis(v, (idx + 1) % N, 1)
    theta = (idx + a / (a - b)) * (2 * np.pi / N)      # crossing angles, ascending
    seg = np.diff(np.concatenate([theta, theta[:, :1] + 2 * np.pi], axis=1), axis=1)
    good = (seg.min(1) >= np.pi / 5) & (seg.max(1) <= np.pi - np.pi / 5)
    # opposite crossings (nearly) collinear: the two lines through the corner
    good &= (np.abs(theta[:, 2] - theta[:, 0] - np.pi) <= 0.45) & (np.abs(theta[:, 3] - theta[:, 1] - np.pi) <= 0.45)
    # every sector clearly on its side: a T-junction (the board border at the median level) has weak ones
    sector = np.cumsum(np.roll(change[rows], 1, axis=1), axis=1) % 4   # sector id of each sample
    amp = 0.5 * (v.max(1) - v.min(1))
    flat = (np.arange(len(rows))[:, None] * 4 + sector).ravel()
    sums = np.bincount(flat, weights=v.ravel(), minlength=4 * len(rows)).reshape(-1, 4)
    cnts = np.bincount(flat, minlength=4 * len(rows)).reshape(-1, 4)
    means = np.abs(sums) / np.maximum(cnts, 1)
    good &= means.min(1) >= 0.35 * amp
    # alternating sectors
    sg = np.sign(sums)
    good &= (sg[:, 0] == sg[:, 2]) & (sg[:, 1] == sg[:, 3]) & (sg[:, 0] != sg[:, 1])
    e = np.exp(1j * theta)
    l1 = np.angle(e[:, 0] - e[:, 2]) % np.pi
    l2 = np.angle(e[:, 1] - e[:, 3]) % np.pi
    ok[rows] = good
    dirs[rows] = np.stack([l1, l2], 1)
    strength[rows] = np.abs(v).mean(1)
    sign[rows] = sg[:, 1]
    return ok, dirs, strength, sign


def find_candidates(f: np.ndarray, sigma: float = 1.2, radii=(3.0, 5.0), noise: float | None = None):
    """Candidates in a normalised image ``f``; also the contrast-normalised smoothed image ``g``,
    its saddle response ``S`` and the local standard deviation (image units)."""
    mu, sd = local_contrast(f)
    # contrast normalisation, but never amplifying flat regions past a few times the noise
    if noise is None:
        noise = image_noise(f)
    floor = max(NOISE_FLOOR * noise, 1e-6)
    g = cv2.GaussianBlur((f - mu) / np.maximum(sd, floor), (0, 0), sigma)
    S = saddle_response(g)
    xy = local_maxima(S, threshold=0.002)
    best = None
    for r in radii:
        if best is None:
            best = list(ring_check(g, xy, r))
        else:                              # the next radius only for those that failed
            rest = np.flatnonzero(~best[0])
            ok, dirs, strength, sign = ring_check(g, xy[rest], r)
            take = rest[ok]
            best[0][take] = True
            for arr, new in zip(best[1:], (dirs, strength, sign)):
                arr[take] = new[ok]
    ok = best[0]
    return Candidates(xy[ok], best[1][ok], best[2][ok], best[3][ok]), g, S, sd
