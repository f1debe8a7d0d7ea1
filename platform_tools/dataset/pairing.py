"""Which frames make the dataset: four-camera pairs, FFC frames out, sampled at a rate.

- Times are header stamps with each stream's own clock steps taken out (the steps the trigger pairing found
  per stream, :mod:`.clocksteps`; the ZED right and depth follow the ZED left).
- Each Boson frame pairs with the ZED left frame of the trigger that exposed it (:mod:`.trigger`: the
  offset of any size, resolved by causality, trigger gaps, the rig's stated latency, continuity
  across clock steps; an ambiguity is an error, never a guess); the ZED right and depth pair with the
  left frame of the same stamp. A pair is complete when each residual is within the tolerance.
- A thermal frame is an FFC frame when its camera's status says an FFC is in progress, or its pixels
  repeat the previous frame's (frozen); it and ``ffc_margin`` frames on each side are dropped
  (kept but flagged with ``keep_ffc``).
- Sampling: slots every 1/rate seconds from the first ZED frame; per slot, the valid pair nearest
  the slot's time.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .layout import NO_DEPTH_HINT
from .recording import THERMAL, Recording
from . import clocksteps
from .sync import corrected_times, ffc_periods, find_clock_steps, pair_residuals, triggers

OTHERS = ("zed_right", "zed_depth", "thermal_left", "thermal_right")


@dataclass
class Pair:
    sample: int
    frames: dict            # stream -> {"stamp_ns", "log_ns", "file"}
    residual_ms: dict       # stream -> ms after the offset
    ffc: dict               # thermal camera -> bool (in an FFC or within the margin)
    ffc_status: dict        # thermal camera -> last status value (-1: no status topic)
    since_ffc_s: dict       # thermal camera -> seconds since its last FFC ended (None: none yet)


@dataclass
class Plan:
    pairs: list[Pair]
    offsets_ms: dict
    clock_steps: list
    counts: dict = field(default_factory=dict)


def _nearest(t_sorted: np.ndarray, x: np.ndarray) -> np.ndarray:
    i = np.clip(np.searchsorted(t_sorted, x), 1, len(t_sorted) - 1)
    left = t_sorted[i - 1]
    return np.where(np.abs(x - left) <= np.abs(t_sorted[i] - x), i - 1, i)


def plan(rec: Recording, rig, *, rate_hz: float, tolerance_ms: float, ffc_margin: int,
         keep_ffc: bool = False, depth: bool = True) -> Plan:
    """``depth``: pair the recorded ZED depth too (False: depth is computed from the stereo pair)."""
    rec.require("thermal_left", "thermal_right", why="the export pairs both thermal cameras with the ZED")
    rec.require("zed_left", "zed_right", why="the export pairs the ZED left and right images")
    if depth:
        rec.require("zed_depth", why="registration of RGB into the thermal views with --depth recorded needs "
                                     "the ZED depth: " + NO_DEPTH_HINT)
    others = OTHERS if depth else tuple(s for s in OTHERS if s != "zed_depth")
    period = 1e9 / rig.desc.sync.rate_hz
    # the Bosons pair by the trigger that exposed each frame (trigger.py), never by the nearest stamp; every
    # stream's stamps lose its own clock's steps (the ZED right and depth: the ZED left's)
    trig = triggers(rec, rig)
    per = {"zed_left": trig.reference.steps} | {c: ct.steps for c, ct in trig.cameras.items()}
    steps = clocksteps.events({n: (v, rec.streams[n].log_ns) for n, v in per.items()},
                              find_clock_steps(rec, period), period)
    tc = corrected_times(rec, per, ("zed_left",) + others, period)
    order = {s: np.argsort(tc[s], kind="stable") for s in tc}
    ref = tc["zed_left"]
    off = {"zed_left": 0.0}
    for s in others[:-2]:
        _, r = pair_residuals(ref, tc[s], period)
        off[s] = float(np.median(r)) if len(r) else 0.0
    match, ok = {}, np.ones(len(ref), bool)
    resid = {}
    for s in others[:-2]:                     # zed_right (zed_depth): the same grab as the left: the same stamp
        ts = tc[s][order[s]]
        j = _nearest(ts, ref + off[s])
        r = ts[j] - (ref + off[s])
        match[s] = order[s][j]
        resid[s] = r / 1e6
        ok &= np.abs(r) <= tolerance_ms * 1e6
    for s in THERMAL:
        ct = trig.cameras[s]
        pos = {int(k): i for i, k in enumerate(ct.trigger) if k >= 0}
        j = np.array([pos.get(int(k), -1) for k in trig.reference.trigger], np.int64)
        have = j >= 0
        match[s] = np.where(have, j, 0)
        resid[s] = np.where(have, ct.residual_ns[match[s]], np.nan) / 1e6
        ok &= have & (np.abs(np.nan_to_num(resid[s], nan=1e9)) <= tolerance_ms)
        off[s] = float(np.average([g.offset_ns for g in ct.segments],
                                  weights=[g.last - g.first + 1 for g in ct.segments]))
    # FFC frames, dilated by the margin (in frames of that camera)
    ffc_flag, periods = {}, {}
    for cam in THERMAL:
        st = rec.streams[cam]
        periods[cam] = ffc_periods(rec, cam, period)
        flag = st.frozen.copy() if st.frozen is not None else np.zeros(len(st.stamp_ns), bool)
        for e in periods[cam]:
            flag |= (st.stamp_ns >= e["start_ns"]) & (st.stamp_ns < e["end_ns"])
        by_time = flag[order[cam]]
        if ffc_margin and by_time.any():
            k = np.ones(2 * ffc_margin + 1)
            by_time = np.convolve(by_time.astype(float), k, mode="same") > 0
        dil = np.zeros_like(flag)
        dil[order[cam]] = by_time
        ffc_flag[cam] = dil
    in_ffc = {cam: ffc_flag[cam][match[cam]] for cam in THERMAL}
    valid = ok & (keep_ffc | ~(in_ffc["thermal_left"] | in_ffc["thermal_right"]))
    # sampling
    P = 1e9 / rate_hz
    t0 = ref.min()
    slot = np.round((ref - t0) / P).astype(np.int64)
    dist = np.abs(ref - (t0 + slot * P))
    chosen: dict[int, int] = {}
    for i in np.nonzero(valid)[0]:
        s = int(slot[i])
        if s not in chosen or dist[i] < dist[chosen[s]]:
            chosen[s] = int(i)
    status = {cam: sorted(rec.status.get(cam) or []) for cam in THERMAL}
    pairs = []
    for s, i in sorted(chosen.items()):
        frames = {"zed_left": i} | {c: int(match[c][i]) for c in others}
        fr = {c: {"stamp_ns": int(rec.streams[c].stamp_ns[j]), "log_ns": int(rec.streams[c].log_ns[j]),
                  "file": int(rec.streams[c].file_index[j])} for c, j in frames.items()}
        fs, since = {}, {}
        for cam in THERMAL:
            t = fr[cam]["stamp_ns"]
            prior = [v for (ts, v) in status[cam] if ts <= t]
            fs[cam] = prior[-1] if prior else -1
            ended = [e["end_ns"] for e in periods[cam] if e["end_ns"] <= t]
            since[cam] = (t - max(ended)) / 1e9 if ended else None
        pairs.append(Pair(s, fr, {c: float(resid[c][i]) for c in others},
                          {cam: bool(in_ffc[cam][i]) for cam in THERMAL}, fs, since))
    counts = {"zed_left_frames": int(len(ref)), "complete": int(ok.sum()),
              "ffc_dropped": int((ok & ~valid).sum()), "sampled": len(pairs)}
    return Plan(pairs, {k: v / 1e6 for k, v in off.items()}, steps, counts)
