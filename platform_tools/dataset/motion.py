"""Image-motion correlation: the last resort for a thermal camera's whole-period trigger offset.

When the trigger period, the stated latency, the trigger gaps and the Boson frame counter (:mod:`.trigger`,
:mod:`.counters`) leave several offsets (phase + n periods) possible, the images still hold the answer when the
scene moves: the ZED left and a Boson exposed by the same trigger pulse see the same motion. Per stream, the
*motion signal* at trigger k is the mean absolute difference between the downsampled frames of triggers k - 1 and
k (frames of two consecutive triggers only; a frozen thermal frame, an FFC, gives none), normalised per stream.
The ZED's signal is correlated with the thermal one laid on the ZED triggers by each candidate n; the offset is
accepted only when

- both streams have at least :data:`MIN_MOVING` samples with motion (above :data:`MOVING_FACTOR` x the stream's
  floor, its :data:`FLOOR_PERCENTILE` th percentile: the sensor noise of a still scene),
- the best candidate's correlation is at least :data:`MIN_CORRELATION` over at least :data:`MIN_COMMON` common
  samples,
- and it beats the runner-up by at least :data:`MIN_MARGIN`.

Otherwise the ambiguity stands and the reason says which of these failed (a still scene: too little motion; a
smooth one: no clear peak). Only a bounded number of frames is read (:data:`WINDOWS` windows of
:data:`WINDOW_TRIGGERS` triggers spread over the segment), each downsampled to :data:`WIDTH_PX` px wide.

The pure functions work on numpy arrays; :class:`Reader` reads the frames of a recording (:mod:`.decode`).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np

#: frames are block-averaged down to about this width (px) before differencing
WIDTH_PX = 64
#: windows read per segment, and triggers per window (bounded reading: 3 x 64 frames per stream)
WINDOWS = 3
WINDOW_TRIGGERS = 64
#: a sample moves when it is above this factor x the stream's floor
MOVING_FACTOR = 1.5
#: the floor of a stream's motion signal (its still-scene noise): this percentile of the signal
FLOOR_PERCENTILE = 10
#: samples with motion needed in each stream
MIN_MOVING = 10
#: common samples (triggers with a motion sample in both streams) needed at the best candidate
MIN_COMMON = 20
#: the best candidate's correlation must reach this ...
MIN_CORRELATION = 0.5
#: ... and beat the runner-up's by this much
MIN_MARGIN = 0.3
#: a normalised sample is clipped at this many robust units (one flash or glitch does not make a peak)
CLIP = 8.0


@dataclass
class Decision:
    n: int | None               # the candidate chosen (periods), None when the motion does not decide
    text: str                   # the evidence (decided) or why the motion did not decide (one phrase)
    report: dict = field(default_factory=dict)


def downsample(img: np.ndarray, width_px: int = WIDTH_PX) -> np.ndarray:
    """(H, W) or (H, W, C) image -> (h, w) float32 grey, block-averaged by ``max(1, W // width_px)`` (units of
    the input)."""
    a = np.asarray(img, np.float32)
    if a.ndim == 3:
        a = a.mean(axis=2)
    f = max(1, a.shape[1] // width_px)
    h, w = (a.shape[0] // f) * f, (a.shape[1] // f) * f
    return a[:h, :w].reshape(h // f, f, w // f, f).mean(axis=(1, 3))


def motion_signal(frames: np.ndarray, trigger: np.ndarray, valid: np.ndarray | None = None
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Motion between frames of consecutive triggers. ``frames``: (N, h, w) downsampled (any units),
    ``trigger``: (N,) int trigger numbers, ``valid``: (N,) bool (False: a frozen frame). Returns (triggers (M,)
    int64: the later trigger of each pair, signal (M,) float64: mean |frame k - frame k-1|, the frames' units)."""
    t = np.asarray(trigger, np.int64)
    order = np.argsort(t, kind="stable")
    t, f = t[order], np.asarray(frames, np.float64)[order]
    ok = np.ones(len(t), bool) if valid is None else np.asarray(valid, bool)[order]
    if len(t) < 2:
        return np.zeros(0, np.int64), np.zeros(0)
    pair = (np.diff(t) == 1) & ok[1:] & ok[:-1]
    m = np.abs(f[1:] - f[:-1]).mean(axis=(1, 2))
    return t[1:][pair], m[pair]


def moving(signal: np.ndarray) -> np.ndarray:
    """(M,) bool: samples above :data:`MOVING_FACTOR` x the stream's floor (plus a hair, for a noiseless still
    scene whose floor is 0)."""
    s = np.asarray(signal, float)
    if len(s) == 0:
        return np.zeros(0, bool)
    floor = float(np.percentile(s, FLOOR_PERCENTILE))
    return s > MOVING_FACTOR * floor + 1e-6 * max(float(np.max(s)), 1e-12)


def normalised(signal: np.ndarray) -> np.ndarray:
    """(M,) the signal less its median, over its robust spread (1.4826 MAD, else the std), clipped at
    :data:`CLIP`: dimensionless, comparable between the ZED's grey levels and the Boson's counts."""
    s = np.asarray(signal, float)
    if len(s) == 0:
        return s
    c = s - np.median(s)
    spread = 1.4826 * float(np.median(np.abs(c))) or float(np.std(c)) or 1.0
    return np.clip(c / spread, -CLIP, CLIP)


def correlations(zk: np.ndarray, zs: np.ndarray, tk: np.ndarray, tsig: np.ndarray,
                 candidates: list[int]) -> dict[int, tuple[float, int]]:
    """Per candidate n: (Pearson correlation, common samples) of the ZED signal ``zs`` at triggers ``zk`` with the
    thermal signal ``tsig`` at base indices ``tk`` (trigger + n, :mod:`.trigger`), laid on trigger ``tk - n``."""
    zpos = {int(k): i for i, k in enumerate(zk)}
    out = {}
    for n in candidates:
        both = [(zpos[int(k) - n], j) for j, k in enumerate(tk) if int(k) - n in zpos]
        if len(both) < 3:
            out[n] = (float("nan"), len(both))
            continue
        i, j = np.array(both).T
        a, b = zs[i], tsig[j]
        if np.std(a) == 0 or np.std(b) == 0:
            out[n] = (float("nan"), len(both))
            continue
        out[n] = (float(np.corrcoef(a, b)[0, 1]), len(both))
    return out


def decide(zk: np.ndarray, zsig: np.ndarray, tk: np.ndarray, tsig: np.ndarray, offsets_ms: dict[int, float]
           ) -> Decision:
    """Which candidate n (``offsets_ms``: n -> its offset after the ZED, ms) the motion signals of the ZED left
    (triggers ``zk``, signal ``zsig``) and the thermal camera (base indices ``tk``, signal ``tsig``) agree on, if
    they do clearly (module docstring); else ``n`` None and why."""
    zmov, tmov = int(moving(zsig).sum()), int(moving(tsig).sum())
    rep = {"zed_samples": int(len(zsig)), "thermal_samples": int(len(tsig)), "zed_moving": zmov,
           "thermal_moving": tmov, "min_moving": MIN_MOVING, "min_correlation": MIN_CORRELATION,
           "min_margin": MIN_MARGIN}
    if zmov < MIN_MOVING or tmov < MIN_MOVING:
        return Decision(None, f"image motion insufficient: the scene had too little motion ({zmov} of {len(zsig)} "
                              f"ZED left and {tmov} of {len(tsig)} thermal frame pairs moved; {MIN_MOVING} needed "
                              f"in each)", rep)
    r = correlations(zk, normalised(zsig), tk, normalised(tsig), list(offsets_ms))
    rep["correlation"] = {f"{offsets_ms[n]:.1f}": (None if np.isnan(c) else round(c, 3)) for n, (c, _) in r.items()}
    ranked = sorted((n for n in r if not np.isnan(r[n][0])), key=lambda n: -r[n][0])
    if not ranked:
        return Decision(None, "image motion insufficient: no candidate has common motion samples with the ZED", rep)
    best = ranked[0]
    rb, nb = r[best]
    second = ranked[1] if len(ranked) > 1 else None
    r2 = r[second][0] if second is not None else -1.0
    rep |= {"best_ms": offsets_ms[best], "best_r": round(rb, 3), "common": nb,
            "runner_up_ms": offsets_ms[second] if second is not None else None, "runner_up_r": round(r2, 3)}
    vs = f"{offsets_ms[second]:.1f} ms" if second is not None else "no other candidate"
    if nb < MIN_COMMON or rb < MIN_CORRELATION or rb - r2 < MIN_MARGIN:
        return Decision(None, f"image motion insufficient: no clear correlation peak (r {rb:.2f} at "
                              f"{offsets_ms[best]:.1f} ms over {nb} frame pairs, {r2:.2f} at {vs}; needed r >= "
                              f"{MIN_CORRELATION:g}, a margin of {MIN_MARGIN:g} and {MIN_COMMON} frame pairs: the "
                              f"scene's motion was too little or too smooth)", rep)
    return Decision(best, f"image motion correlation with the ZED left (r {rb:.2f} over {nb} frame pairs, "
                          f"runner-up {r2:.2f} at {vs}; margin {rb - r2:.2f} >= {MIN_MARGIN:g})", rep)


def windows(lo: int, hi: int, count: int = WINDOWS, size: int = WINDOW_TRIGGERS) -> list[tuple[int, int]]:
    """Up to ``count`` windows of ``size`` triggers, evenly spread over [lo, hi] (inclusive); the whole range when
    it is no longer than their total."""
    if hi - lo + 1 <= count * size:
        return [(lo, hi)]
    starts = np.linspace(lo, hi - size + 1, count).round().astype(np.int64)
    return [(int(s), int(s) + size - 1) for s in starts]


class Reader:
    """Downsampled frames of one recording, read on demand and kept (both thermal cameras share the ZED's)."""

    def __init__(self, rec, rig):
        self.rec, self.rig = rec, rig
        self._cache: dict[tuple[str, int], np.ndarray] = {}

    def frames(self, stream: str, index: np.ndarray) -> np.ndarray:
        """(frames (N, h, w) float32 downsampled, their recording-order indices (N,)) of ``stream`` at ``index``,
        those that could be read (thermal: image rows only, the telemetry rows cut)."""
        from .decode import iter_frames
        from .recording import telemetry_rows
        st = self.rec.streams[stream]
        todo = [int(i) for i in index if (stream, int(i)) not in self._cache]
        if todo:
            wanted = {(st.topic, int(st.stamp_ns[i])): i for i in todo}
            files = sorted({int(st.file_index[i]) for i in todo})
            for i, _, img in iter_frames([str(self.rec.files[f]) for f in files], wanted,
                                         [int(st.log_ns[i]) for i in todo]):
                if stream.startswith("thermal"):
                    img = img[:img.shape[0] - telemetry_rows(self.rig, img.shape[1], img.shape[0])]
                self._cache[(stream, i)] = downsample(img)
        got = [int(i) for i in index if (stream, int(i)) in self._cache]
        if not got:
            return np.zeros((0, 1, 1), np.float32), np.zeros(0, np.int64)
        return np.stack([self._cache[(stream, i)] for i in got]), np.array(got, np.int64)

    def resolver(self, camera: str, zed_trigger: np.ndarray):
        """The ``motion`` argument of :func:`.trigger.assign` for ``camera``: ``(first, base, offsets_ms) ->
        Decision`` for the segment whose frames ``first..first + len(base) - 1`` have base indices ``base``."""
        st = self.rec.streams[camera]
        kz = np.asarray(zed_trigger, np.int64)

        def decide_segment(first: int, base: np.ndarray, offsets_ms: dict[int, float]) -> Decision:
            base = np.asarray(base, np.int64)
            cands = list(offsets_ms)
            ti, zi = [], []
            for lo, hi in windows(int(base.min()), int(base.max())):
                ti += (first + np.nonzero((base >= lo) & (base <= hi))[0]).tolist()
                zi += np.nonzero((kz >= lo - max(cands) - 1) & (kz <= hi - min(cands)))[0].tolist()
            try:
                tf, ti = self.frames(camera, np.array(sorted(set(ti)), np.int64))
                zf, zi = self.frames("zed_left", np.array(sorted(set(zi)), np.int64))
            except (ValueError, cv2.error) as exc:        # an undecodable image: no motion evidence, said
                return Decision(None, f"image motion not read ({type(exc).__name__}: {exc})")
            frozen = st.frozen[ti] if st.frozen is not None and len(ti) else np.zeros(len(ti), bool)
            tk, tsig = motion_signal(tf, base[ti - first], ~frozen)
            zk, zsig = motion_signal(zf, kz[zi])
            d = decide(zk, zsig, tk, tsig, offsets_ms)
            d.report["frames_read"] = {"zed_left": int(len(zi)), camera: int(len(ti))}
            return d

        return decide_segment
