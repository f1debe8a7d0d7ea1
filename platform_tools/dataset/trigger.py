"""Which trigger pulse exposed each frame: pairing by trigger, not by nearest stamp.

The ZED left defines the trigger numbering (its stamp is the trigger's, plus a constant). For every
other camera the stamps alone give the offset only modulo one trigger period (its *phase*); the
whole number of periods is the ambiguity this module resolves, per *segment* (the recording cut at
every clock step of either stream), from the evidence the recording holds:

1. **Causality**: a frame is never stamped before its trigger (offset >= -3 sigma of its jitter).
2. **Trigger gaps**: a trigger pulse that never came is missing from every camera at the same trigger;
   the candidate offset that lines the gaps of both streams up is the right one. With the Boson's
   telemetry frame counter (:mod:`.counters`), a thermal gap whose counter did not skip is a missing
   pulse (an anchor); one whose counter skipped is a host drop (not an anchor), so fewer gaps decide.
3. **The rig's stated latency** (``sync.stamp_latency_ms``): a window narrower than a period leaves
   one candidate.
4. **Image motion** (last resort, :mod:`.motion`, given as ``assign(..., motion=...)``): when the above leave
   several candidates, the ZED left's and the Boson's per-frame motion signals correlated over them; used only
   with a clear peak, else the reason joins the missing evidence.

Evidence that disagrees, or none that leaves exactly one candidate, ends in :class:`TriggerError`
(one line: file, topic, the candidates and the evidence missing), never in a guess.

**Clock steps per stream**: each stream's stamps minus their trigger grid (local indices from the
intervals, ``max(1, round(interval / period))``) are constant but for jitter; a step is where the
median of the frames after differs from the median before by more than ``STEP_MIN_NS``. Backward steps
(either sign, any size) are sized exactly; a forward step is known modulo one period unless the
segments' alignment, the IMU or the frame counter says how many periods it held, or the evidence
:mod:`.clocksteps` reads (the recorder's log times, the device's status) does. A ZED-clock step the IMU
sizes takes the IMU's size whole (:func:`imu_step_size`), not only its whole periods: the stamps' medians miss
the fraction by a tenth of a millisecond, which moves every corrected time after the step. With the frame counter
a thermal stream's steps are found on the counter's trigger grid, at their full size.

Pure functions over stamp arrays (numpy); no I/O.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from . import counters

#: IMU samples on each side of a ZED-clock step whose fitted grids size it (:func:`imu_step_size`; 0.25 s at 200 Hz)
IMU_STEP_WINDOW = 50
#: a clock step smaller than this is not told apart from jitter (the issue asks for 5 ms)
STEP_MIN_NS = 2_500_000
#: frames on each side of a candidate step whose medians are compared
STEP_WINDOW = 8
#: anchors needed without a frame counter to classify the gaps (chance coincidences of host drops)
MIN_ANCHORS_WITHOUT_COUNTER = 3
#: anchors needed with the frame counter (every one a pulse the Boson never got; one alone could be a pulse
#: missed by that Boson only, on a trigger where the ZED happened to drop a frame)
MIN_ANCHORS_WITH_COUNTER = 2
#: with the frame counter the gaps decide when every other offset puts at least this many more of the
#: counter's missing pulses on ZED frames (contradictions) than the best one
COUNTER_LEAD = 2
#: a frame this far (or 6 robust sigmas) from its segment's trigger grid is left unassigned
UNFIT_MIN_NS = 4_000_000
#: candidate offsets searched, in periods
MAX_PERIODS = 8
#: the trigger gaps decide when the best offset lines up more than this many times the runner-up's
#: common gaps (two adjacent missing pulses give the offset one period off a common gap too)
GAP_DOMINANCE = 2


class TriggerError(Exception):
    """The trigger of some frames cannot be established; ``str()`` is one line."""


@dataclass
class Step:
    index: int                  # first frame (recording order) after the step
    at_ns: int                  # its stamp as recorded
    step_ns: int                # size (wrapped to one period when sized by stamps alone, forward)
    exact: bool                 # sized without the modulo-one-period ambiguity
    sized_by: str = "stamps"    # "stamps", "imu", "frame counter", "log times" or "device status"
    #: the sizes the stamps allow (:func:`.clocksteps.candidates`), when the step was known modulo a period
    candidates_ns: list = field(default_factory=list)
    #: how the whole number of periods was chosen, or why it could not be (one phrase; :mod:`.clocksteps`)
    evidence: str = ""


@dataclass
class Segment:
    first: int                  # frame range [first, last] of the camera (recording order)
    last: int
    offset_ns: float            # camera stamp - ZED left stamp of the same trigger
    uncertainty_ns: float       # standard error of that offset
    established_by: str
    candidates_ms: list[float]
    #: the image-motion correlation's figures when it was consulted (motion.Decision.report), else None
    motion: dict | None = None


@dataclass
class CameraTriggers:
    camera: str
    trigger: np.ndarray         # int64: trigger number of each frame (ZED left numbering; -1: none), recording order
    residual_ns: np.ndarray     # stamp - (ZED grid at that trigger) - segment offset
    segments: list[Segment]
    steps: list[Step]
    jitter_ns: float
    host_drops: int = 0
    anchors: int = 0
    missing_pulses: int = 0     # pulses the frame counter says never reached the camera
    repeated: int = 0           # frames whose counter did not advance
    counter: bool = False       # the frame counter was read


@dataclass
class Assignment:
    period_ns: float
    reference: CameraTriggers   # the ZED left
    cameras: dict[str, CameraTriggers] = field(default_factory=dict)
    #: camera -> why its telemetry frame counter was not used (one line), when it was not
    ignored_counters: dict[str, str] = field(default_factory=dict)


# ----------------------------------------------------------------------------- one stream
def local_indices(t: np.ndarray, period_ns: float) -> np.ndarray:
    """Trigger count of each frame since the first, from the intervals (a backward step still counts
    as one period: a frame never comes less than a period after the last)."""
    d = np.diff(t.astype(np.int64))
    m = np.maximum(1, np.round(d / period_ns).astype(np.int64))
    return np.concatenate([[0], np.cumsum(m)])


def find_steps(t: np.ndarray, k: np.ndarray, period_ns: float, window: int = STEP_WINDOW,
               min_ns: float = STEP_MIN_NS) -> list[Step]:
    """Clock steps of one stream: where the residual to its trigger grid changes level."""
    r = (t - t[0] - k * period_ns).astype(float)
    n = len(r)
    if n < 2 * window + 1:
        return []
    med = np.median(sliding_window_view(r, window), axis=1)      # med[j] = median(r[j:j+window])
    i = np.arange(window, n - window + 1)
    jump = med[i] - med[i - window]
    steps, j = [], 0
    big = np.abs(jump) > min_ns
    while j < len(i):
        if not big[j]:
            j += 1
            continue
        e = j
        while e + 1 < len(i) and big[e + 1] and np.sign(jump[e + 1]) == np.sign(jump[j]):
            e += 1
        # the step is at the one interval of the plateau that carries it (medians are flat around it)
        lo, hi = int(i[j]), int(i[e])
        sign = np.sign(jump[j])
        at = lo + int(np.argmax(sign * (r[lo:hi + 1] - r[lo - 1:hi])))
        size = float(np.median(r[at:at + window]) - np.median(r[at - window:at]))
        # from stamps alone a step is known modulo one period (a frame dropped at the step shifts it by
        # one); the IMU (reference()) sizes it exactly
        steps.append(Step(at, int(t[at]), int(round(size)), exact=False))
        j = e + 1
    return steps


def segments_of(n: int, cuts: list[int]) -> list[tuple[int, int]]:
    edges = [0] + sorted(set(c for c in cuts if 0 < c < n)) + [n]
    return [(a, b - 1) for a, b in zip(edges[:-1], edges[1:]) if b > a]


def reference(t: np.ndarray, period_ns: float, imu: np.ndarray | None = None) -> CameraTriggers:
    """The ZED left: its frames define the trigger numbering (steps found, the grid fitted per segment).
    The IMU (same clock, 200 Hz, no drops in practice) sizes a forward step exactly."""
    k = local_indices(t, period_ns)
    steps = find_steps(t, k, period_ns)
    ref = CameraTriggers("zed_left", k, np.zeros(len(t)), [Segment(0, len(t) - 1, 0.0, 0.0, "reference", [0.0])],
                         steps, 0.0)
    if imu is not None and len(imu) > 10:
        di = np.diff(imu.astype(np.int64))
        med = float(np.median(di))
        for st in steps:
            if st.exact:
                continue
            lo, hi = int(t[st.index - 1]), int(t[st.index])
            near = np.nonzero((imu[1:] >= min(lo, hi) - 2 * period_ns) & (imu[:-1] <= max(lo, hi) + 2 * period_ns))[0]
            if len(near):
                j = near[np.argmax(np.abs(di[near] - med))]
                size = imu_step_size(imu, int(j), med)
                if abs(size) >= STEP_MIN_NS and abs(((size - st.step_ns) / period_ns) - round((size - st.step_ns) / period_ns)) < 0.1:
                    # the IMU's size, not the whole periods it adds to the stamps' estimate: the medians of
                    # STEP_WINDOW jittery frames miss it by a tenth of a millisecond and more, and every corrected
                    # time after the step (the sampling's slots) would carry that error
                    size_step(ref, t, st, int(round(size)),
                              "imu", "the IMU's grid on each side of it (same clock, 200 Hz)", period_ns, refit=False)
    _refit(ref, t)
    return ref


def imu_step_size(imu: np.ndarray, j: int, period_ns: float, window: int = IMU_STEP_WINDOW) -> float:
    """Size (ns) of the clock step in the IMU's interval ``j`` (between samples ``j`` and ``j + 1``; ``imu``: (n,)
    stamps in ns, recording order; ``period_ns``: its median interval): the IMU's grid fitted by least squares on
    up to ``window`` samples each side (up to the next irregular interval: another step, a lost sample), both lines
    extrapolated to the interval, less the mean of their periods. With a single sample on both sides: the interval
    less ``period_ns``."""
    t = imu.astype(np.int64) - int(imu[j])               # ns relative to the last sample before the step
    d = np.diff(t)
    regular = np.abs(d / period_ns - 1.0) < 0.25

    def side(first: int, last: int, anchor: int):
        """(value at the anchor sample in ns, period in ns or None) of the line through samples first..last."""
        y = t[first:last + 1].astype(float)
        if len(y) < 2:
            return float(y[0]), None
        slope, icpt = np.polyfit((np.arange(first, last + 1) - anchor).astype(float), y, 1)
        return float(icpt), float(slope)

    a = j
    while a > 0 and j - a + 1 < window and regular[a - 1]:
        a -= 1
    b = j + 1
    while b + 1 < len(t) and b - j < window and regular[b]:
        b += 1
    before, p_before = side(a, j, j)
    after, p_after = side(j + 1, b, j + 1)
    periods = [p for p in (p_before, p_after) if p is not None]
    if not periods:
        return float(d[j] - period_ns)
    return after - before - float(np.mean(periods))


def size_step(ref: CameraTriggers, t: np.ndarray, st: Step, size_ns: int, by: str, evidence: str,
              period_ns: float, refit: bool = True) -> None:
    """Give a step of the ZED left (``ref``) its full size: the triggers that passed over it follow (the trigger
    numbering after it), and the grid residuals."""
    st.step_ns, st.exact, st.sized_by, st.evidence = int(size_ns), True, by, evidence
    d = int(t[st.index]) - int(t[st.index - 1])
    k = ref.trigger
    k[st.index:] += max(1, round((d - st.step_ns) / period_ns)) - (k[st.index] - k[st.index - 1])
    if refit:
        _refit(ref, t)


def _refit(ref: CameraTriggers, t: np.ndarray) -> None:
    res = np.zeros(len(t))
    for a, b in segments_of(len(t), [s.index for s in ref.steps]):
        res[a:b + 1] = _grid_residual(t[a:b + 1], ref.trigger[a:b + 1])
    ref.residual_ns = res
    ref.jitter_ns = float(np.std(res)) if len(res) > 2 else 0.0


def _grid_residual(t: np.ndarray, k: np.ndarray) -> np.ndarray:
    if len(t) < 2:
        return np.zeros(len(t))
    slope, icpt = np.polyfit(k.astype(float), (t - t[0]).astype(float), 1)
    return (t - t[0]) - (icpt + slope * k)


def _grid(tz: np.ndarray, kz: np.ndarray, steps: list[Step]):
    """Per ZED segment: (first stamp, last stamp, intercept, period) of its fitted trigger grid."""
    out = []
    for a, b in segments_of(len(tz), [s.index for s in steps]):
        kk, tt = kz[a:b + 1].astype(float), tz[a:b + 1].astype(float)
        if len(tt) >= 2:
            slope, icpt = np.polyfit(kk, tt - tz[0], 1)
        else:
            slope, icpt = None, float(tt[0] - tz[0])
        out.append((int(tz[a]), int(tz[b]), icpt + float(tz[0]), slope))
    return out


# ----------------------------------------------------------------------------- another camera
def assign(tz: np.ndarray, ts: np.ndarray, period_ns: float, *, camera: str, window_ms: tuple[float, float] | None,
           counter: np.ndarray | None = None, ref: CameraTriggers | None = None,
           where: str = "", motion=None, size_steps=None) -> CameraTriggers:
    """Trigger number of every frame of one camera, in the ZED left's numbering. ``motion``: the last resort,
    ``(first frame, base indices of the segment's frames, {candidate n: offset ms}) -> motion.Decision``
    (:meth:`.motion.Reader.resolver`), asked only when the other evidence leaves several candidates.
    ``size_steps``: given this stream's own clock steps, sizes those known modulo a period when other evidence
    can (:func:`.clocksteps.thermal_sizer`: the recorder's log times, the device's status)."""
    ref = ref or reference(tz, period_ns)
    kz = ref.trigger
    zgrid = _grid(tz, kz, ref.steps)
    own = counter_steps(ts, counter, period_ns) if counter is not None else \
        find_steps(ts, local_indices(ts, period_ns), period_ns)
    if size_steps is not None:
        size_steps(own)
    # cut where either stream's clock stepped: the camera's own steps, and the ZED's (mapped to this
    # stream: the same event when this stream stepped there too, else where its stamps pass the ZED's
    # last stamp before the step, both still on the clock before it)
    cuts: dict[int, dict] = {o.index: {"own": o, "zed": None} for o in own}
    running = np.maximum.accumulate(ts)
    for z in ref.steps:
        pre = int(tz[z.index - 1])
        same = [o.index for o in own if abs(int(ts[o.index - 1]) - pre) < 3 * period_ns]
        i = same[0] if same else int(np.searchsorted(running, pre + period_ns / 2))
        cuts.setdefault(i, {"own": None, "zed": None})["zed"] = z
    gaps_by_counter = counters.classify(ts, counter, period_ns, {o.index for o in own}) \
        if counter is not None else None
    zmissing = set(np.setdiff1d(np.arange(kz[0], kz[-1] + 1), kz).tolist())
    trig = np.zeros(len(ts), np.int64)
    resid = np.zeros(len(ts))
    segs = []
    cand_default_p = period_ns if not zgrid or zgrid[0][3] is None else zgrid[0][3]
    n_anchor_total = 0
    for a, b in segments_of(len(ts), list(cuts)):
        t = ts[a:b + 1].astype(np.int64)
        # the ZED grid of this segment: as many ZED steps before it as cuts from ZED steps
        gi = min(sum(1 for i, c in cuts.items() if i <= a and c["zed"] is not None), len(zgrid) - 1)
        _, _, icpt, slope = zgrid[gi]
        P = slope or cand_default_p
        x = (t - icpt) / P
        frac = np.mod(x, 1.0)
        ang = np.angle(np.mean(np.exp(2j * np.pi * frac)))
        phase = float(np.mod(ang / (2 * np.pi), 1.0))                  # in [0, 1) periods
        base = np.round(x - phase).astype(np.int64)                   # ZED trigger whose grid is `phase` before
        dev = (x - phase - base) * P
        sigma = float(np.std(dev)) if len(dev) > 2 else 0.0
        unc = sigma / np.sqrt(max(len(dev), 1))
        evidence = []
        after_unknown_step = None
        # continuity across the step that starts this segment, when its size is known exactly (or the
        # same step hit both clocks: then its size cancels)
        cut = cuts.get(a)
        if segs and cut is not None:
            o, z = cut["own"], cut["zed"]
            # the same step on both clocks (matched in time): sizes agree, or agree modulo a period
            # when one of them is known exactly
            both = (o is not None and z is not None and abs(_wrap(o.step_ns - z.step_ns, P)) < 3e6
                    and (abs(o.step_ns - z.step_ns) < 3e6 or o.exact or z.exact))
            if not both and not all(st is None or st.exact for st in (o, z)):
                # one clock stepped forward by a size known modulo a period: the clocks now differ by an
                # unknown number of periods, so the stated latency says nothing; only trigger gaps can tell
                after_unknown_step = (o or z)
            if both or all(st is None or st.exact for st in (o, z)):
                d = 0 if both else (o.step_ns if o else 0) - (z.step_ns if z else 0)
                pred = segs[-1].offset_ns + d
                n = int(round(pred / P - phase))
                if abs((phase + n) * P - pred) < max(3e6, 5 * sigma):
                    trig[a:b + 1] = np.where(_unfit(dev), -1, base - n)
                    resid[a:b + 1] = dev
                    what = "both clocks" if both else ("this clock" if o else "the ZED clock")
                    by = sorted({st.sized_by for st in (o, z) if st is not None and st.exact})
                    if by and not both:
                        what += ", sized by the " + " and the ".join(by)
                    segs.append(Segment(a, b, (phase + n) * P, unc,
                                        f"continuity across a step of {d / 1e6 if not both else o.step_ns / 1e6:+.1f}"
                                        f" ms ({what})", [round((phase + n) * P / 1e6, 3)]))
                    continue
        margin = max(1e6, 3 * sigma)
        seen = None                     # the image-motion decision, when it was asked
        cands = [n for n in range(-1, MAX_PERIODS + 1) if (phase + n) * P >= -margin]
        evidence = []
        # trigger gaps: base indices missing in this segment
        if gaps_by_counter is not None:
            # each gap holds q pulses the Boson never got, somewhere among its triggers: at the right offset q
            # of them are holes of the ZED grid (matches); each one short is a contradiction
            held = _gap_triggers(base, gaps_by_counter.missing[a:b + 1])
            gaps = [t for pos, _ in held for t in pos]
            holes = {n: [sum((t - n) in zmissing for t in pos) for pos, _ in held] for n in cands}
            scores = {n: sum(min(q, h) for (_, q), h in zip(held, holes[n])) for n in cands}
            against = {n: sum(max(q - h, 0) for (_, q), h in zip(held, holes[n])) for n in cands}
        else:
            gaps = _base_gaps(base)
            scores = {n: len([g for g in gaps if (g - n) in zmissing]) for n in cands}
        need = MIN_ANCHORS_WITH_COUNTER if counter is not None else MIN_ANCHORS_WITHOUT_COUNTER
        ranked = sorted(scores.items(), key=lambda kv: -kv[1])
        by_gaps = None
        if counter is not None:
            # every counter gap is a pulse the Boson never got: at a wrong offset it lands on a ZED frame
            # (a contradiction), at the right one on a ZED hole unless the Boson alone missed it
            decisive = bool(ranked) and all(against[n] - against[ranked[0][0]] >= COUNTER_LEAD
                                            for n in cands if n != ranked[0][0])
        else:
            decisive = bool(ranked) and (len(ranked) == 1 or ranked[0][1] > GAP_DOMINANCE * ranked[1][1])
        if ranked and ranked[0][1] >= need and decisive:
            by_gaps = ranked[0][0]
            n_anchor_total += ranked[0][1]
        in_window = cands
        if after_unknown_step is not None:
            in_window = []
        elif window_ms is not None:
            lo, hi = window_ms[0] * 1e6 - 3 * unc - margin / 3, window_ms[1] * 1e6 + 3 * unc + margin / 3
            in_window = [n for n in cands if lo <= (phase + n) * P <= hi]
        cand_ms = [round((phase + n) * P / 1e6, 3) for n in cands if (phase + n) * P <= 4 * period_ns]
        if by_gaps is not None:
            n = by_gaps
            evidence.append(f"trigger gaps ({scores[n]} common with the ZED"
                            + (", classified by the frame counter" if counter is not None else "") + ")")
            if counter is not None and against[n]:
                evidence.append(f"{against[n]} pulse(s) the counter says this Boson missed "
                                f"were seen by the ZED (missed by this Boson alone)")
            if window_ms is not None and n not in in_window:
                evidence.append(f"outside the rig's stated latency {window_ms[0]:g}..{window_ms[1]:g} ms: "
                                f"measure it and correct sync.stamp_latency_ms.{camera}")
        elif len(in_window) == 1 and ranked and ranked[0][1] >= need and scores[in_window[0]] < ranked[0][1]:
            # the stated latency picks one offset, the trigger gaps lean to another without deciding:
            # evidence that disagrees is a refusal, never the window's guess
            w, g = in_window[0], ranked[0][0]
            raise TriggerError(
                f"{where}{camera}: which trigger exposed frames {a}..{b} is ambiguous: the rig's stated latency "
                f"(sync.stamp_latency_ms.{camera}: {window_ms[0]:g}..{window_ms[1]:g} ms) gives "
                f"{(phase + w) * P / 1e6:.1f} ms, the trigger gaps common with the ZED favour {(phase + g) * P / 1e6:.1f} "
                f"ms ({scores[g]} against {scores[w]}, not decisive); missing evidence: a measured latency"
                + (f" (the frame counter's missing pulses fall on {against[w]} ZED frame(s) at the first, "
                   f"{against[g]} at the second: fewer than {COUNTER_LEAD} apart)" if counter is not None
                   else " or the Boson frame counter (telemetry rows)"))
        elif len(in_window) == 1:
            n = in_window[0]
            evidence.append("causality + the rig's stated latency "
                            f"(sync.stamp_latency_ms.{camera}: {window_ms[0]:g}..{window_ms[1]:g} ms)"
                            if window_ms is not None else "causality")
        elif motion is not None and (seen := motion(a, base, {m: (phase + m) * P / 1e6 for m in (in_window or cands)})
                                     ).n is not None:
            n = seen.n
            evidence.append(seen.text)
        else:
            ms = ", ".join(f"{(phase + m) * P / 1e6:.1f}" for m in (in_window or cands)[:4])
            missing = []
            if after_unknown_step is not None:
                st = after_unknown_step
                clock = "the ZED clock" if st is (cut or {}).get("zed") else "this camera's clock"
                sizes = ", ".join(f"{c / 1e6:+.1f}" for c in st.candidates_ns[:4]) or f"{st.step_ns / 1e6:+.1f}"
                missing.append(f"{clock} stepped at stamp {st.at_ns} by {st.step_ns / 1e6:+.1f} ms modulo one "
                               f"period (candidates {sizes} ms: 0, 1, 2... frames lost at it); nothing sized it: "
                               + (st.evidence or "record the IMU to size a ZED-clock step"))
            elif window_ms is None:
                missing.append(f"no stated latency (sync.stamp_latency_ms.{camera})")
            elif not in_window:
                missing.append(f"no candidate inside the stated latency {window_ms[0]:g}..{window_ms[1]:g} ms "
                               f"(sync.stamp_latency_ms.{camera})")
            else:
                missing.append(f"the stated latency {window_ms[0]:g}..{window_ms[1]:g} ms "
                               f"(sync.stamp_latency_ms.{camera}) spans more than one trigger period")
            missing.append(f"{'no' if not gaps else 'too few'} common trigger gaps"
                           + ("" if counter is not None else " and no Boson frame counter (telemetry rows)"))
            if motion is not None:
                missing.append(seen.text)
            raise TriggerError(f"{where}{camera}: which trigger exposed frames {a}..{b} is ambiguous: offsets "
                               f"{ms} ms after the ZED all fit; missing evidence: {'; '.join(missing)}")
        trig[a:b + 1] = np.where(_unfit(dev), -1, base - n)
        resid[a:b + 1] = dev
        segs.append(Segment(a, b, (phase + n) * P, unc, "; ".join(evidence), cand_ms,
                            motion=seen.report if seen is not None else None))
    _refine_counter_steps(own, cuts, segs)
    jit = float(np.std(resid)) if len(resid) > 2 else 0.0
    g = gaps_by_counter
    return CameraTriggers(camera, trig, resid, segs, own, jit, host_drops=g.host_drops if g else 0,
                          anchors=n_anchor_total, missing_pulses=g.missing_pulses if g else 0,
                          repeated=g.repeated if g else 0, counter=g is not None)


def _refine_counter_steps(own: list[Step], cuts: dict, segs: list[Segment]) -> None:
    """A step the frame counter sized is also the change of offset between the segments around it (every
    frame of both, rather than the medians of a few): take that, the ZED's own step added back."""
    for k in range(1, len(segs)):
        cut = cuts.get(segs[k].first)
        o = cut["own"] if cut else None
        if o is None or o.sized_by != "frame counter" or (cut["zed"] is not None and not cut["zed"].exact):
            continue
        o.step_ns = int(round(segs[k].offset_ns - segs[k - 1].offset_ns + (cut["zed"].step_ns if cut["zed"] else 0)))
        if cut["zed"] is None:      # the text names the step's size: the refined one
            segs[k].established_by = re.sub(r"a step of [+-][\d.]+ ms", f"a step of {o.step_ns / 1e6:+.1f} ms",
                                            segs[k].established_by)


def _unfit(dev: np.ndarray) -> np.ndarray:
    """Frames too far from their segment's grid to be assigned (a step's frame on the wrong side): -1."""
    mad = float(np.median(np.abs(dev - np.median(dev)))) * 1.4826 if len(dev) > 4 else 0.0
    return np.abs(dev) > max(UNFIT_MIN_NS, 6 * mad)


def _wrap(x: float, period: float) -> float:
    return (x + period / 2) % period - period / 2


def counter_steps(ts: np.ndarray, counter: np.ndarray, period_ns: float) -> list[Step]:
    """Clock steps of a thermal stream found on the frame counter's trigger grid: exact, either sign, any size
    (a level change of a whole number of periods is pulses that never came, :mod:`.counters`)."""
    k = counters.pulse_grid_index(ts, counter, period_ns)
    return [Step(st.index, st.at_ns, st.step_ns, exact=True, sized_by="frame counter")
            for st in find_steps(ts, k, period_ns) if not counters.is_missing_pulses(st.step_ns, period_ns)]


def _gap_triggers(base: np.ndarray, missing: np.ndarray) -> list[tuple[list[int], int]]:
    """Per gap that holds pulses the counter says never came: (its base indices, how many of them)."""
    return [(list(range(int(base[i - 1]) + 1, int(base[i]))), int(missing[i]))
            for i in range(1, len(base)) if missing[i] > 0 and base[i] - base[i - 1] > 1]


def _base_gaps(base: np.ndarray) -> list[int]:
    """Base indices missing between consecutive frames (host drops and missing pulses alike)."""
    out = []
    for i in range(1, len(base)):
        if base[i] - base[i - 1] > 1:
            out += list(range(int(base[i - 1]) + 1, int(base[i])))
    return out
