"""Clock steps known modulo one trigger period: their candidate sizes, and the evidence that picks one.

From a stream's stamps alone (:func:`.trigger.find_steps`) a step is known modulo one trigger period: the
interval that holds it is (triggers passed) x period + step, and how many triggers passed is known only if no
frame was lost right at the step. The candidates (:func:`candidates`) are the stamps' size plus a whole number of
periods, one per number of frames lost at the step (0 .. :data:`MAX_LOST`). What picks one:

1. **the IMU** (same clock as the ZED, 200 Hz; :func:`.trigger.reference`) for a ZED-clock step;
2. **the Boson frame counter** (:func:`.trigger.counter_steps`) for a thermal-clock step;
3. **the recorder's log times** (:func:`log_time_step`), a third clock common to every stream: across a step of
   stream A, ``log - stamp`` of A changes by ``r - s_A`` and that of stream B, over the same log-time instant, by
   ``r - s_B``, whatever the recorder's own clock did (``r``: it follows the host clock when the host is
   stepped). So ``s_A - s_B`` is measured to the transport jitter, whichever clock stepped; it picks the
   candidate within :data:`LOG_TOLERANCE_NS` (and 4 standard errors) of it, when exactly one is;
4. **trigger gaps** common to the ZED and the Boson after the step (:func:`.trigger.assign`, per segment).

Otherwise the step keeps its candidates and the reason each source could not tell (``Step.evidence``), and the
pairing across it is refused naming them: never a silent off-by-one trigger.

Pure functions over numpy arrays and :class:`.trigger.Step` objects; no I/O.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import trigger as trig

#: frames lost at the step considered (each is one more candidate size, one period smaller)
MAX_LOST = 3
#: frames of each stream compared on each side of a step, and frames skipped right at it
LOG_WINDOW = 16
LOG_GUARD = 2
#: frames needed on each side for a log-time measurement
LOG_MIN_FRAMES = 5
#: a log-time measurement picks a candidate this close (and within 4 standard errors); a quarter period leaves
#: the next candidate three quarters of a period away
LOG_TOLERANCE_NS = 1e9 / 30 / 4


@dataclass(frozen=True)
class Measured:
    """A relative clock step (stream A's step minus stream B's) measured on the recorder's log times."""
    step_ns: float
    stderr_ns: float
    against: str                # stream B


def candidates(st: "trig.Step", triggers_passed: int, period_ns: float) -> list[int]:
    """The sizes a step found by the stamps can have: one per number of frames lost at it (0, 1, ...), whole
    periods apart. ``triggers_passed``: what the stream's trigger numbering counted over the step's interval
    (``k[i] - k[i-1]``) for the size ``st.step_ns``."""
    return [int(round(st.step_ns + (triggers_passed - 1 - lost) * period_ns)) for lost in range(MAX_LOST + 1)]


def _robust(x: np.ndarray) -> tuple[float, float]:
    """(median, its standard error from the MAD)."""
    med = float(np.median(x))
    mad = float(np.median(np.abs(x - med))) * 1.4826
    return med, 1.25 * max(mad, 1e5) / np.sqrt(len(x))


def log_time_step(stamp_a: np.ndarray, log_a: np.ndarray, i: int, stamp_b: np.ndarray, log_b: np.ndarray,
                  period_ns: float, against: str = "") -> Measured | str:
    """Stream A's clock step at its frame ``i`` (recording order) minus stream B's over the same instant, from
    ``log - stamp`` of each (see the module docstring); a phrase saying why not when the log times cannot tell."""
    ua = log_a.astype(np.int64) - stamp_a.astype(np.int64)
    ub = log_b.astype(np.int64) - stamp_b.astype(np.int64)
    if not ua.any() and not ub.any():
        return "the log times are the header stamps (no receive clock)"
    before_a = ua[max(0, i - LOG_GUARD - LOG_WINDOW):max(0, i - LOG_GUARD)]
    after_a = ua[i + LOG_GUARD:i + LOG_GUARD + LOG_WINDOW]
    lo, hi = int(log_a[i - 1]) - LOG_GUARD * period_ns, int(log_a[i]) + LOG_GUARD * period_ns
    before_b = ub[log_b < lo][-LOG_WINDOW:]
    after_b = ub[log_b > hi][:LOG_WINDOW]
    if min(len(before_a), len(after_a), len(before_b), len(after_b)) < LOG_MIN_FRAMES:
        return f"fewer than {LOG_MIN_FRAMES} frames on a side of the step to compare log times"
    (ma0, ea0), (ma1, ea1) = _robust(before_a), _robust(after_a)
    (mb0, eb0), (mb1, eb1) = _robust(before_b), _robust(after_b)
    return Measured((mb1 - mb0) - (ma1 - ma0), float(np.sqrt(ea0 ** 2 + ea1 ** 2 + eb0 ** 2 + eb1 ** 2)),
                    f"log - stamp against {against}")


def device_status_step(log_a: np.ndarray, i: int, stamp_b: np.ndarray, log_b: np.ndarray,
                       clock_step: dict[int, int], period_ns: float, against: str = "") -> Measured | str:
    """The host clock's step at stream A's frame ``i`` as the device saw it from a Boson stream B: the change of
    ``clock_step_ns`` (CLOCK_REALTIME - CLOCK_MONOTONIC since usb_cam started; firmware/device/clockstep.py) in
    the status of B's frames (``clock_step``: frame stamp -> value) over the same log-time instant. usb_cam's
    stamps do not follow a host step and the ZED's do, so it is the ZED's step minus the Boson's."""
    lo, hi = int(log_a[i - 1]) - LOG_GUARD * period_ns, int(log_a[i]) + LOG_GUARD * period_ns
    vals = np.array([clock_step.get(int(t), np.iinfo(np.int64).min) for t in stamp_b], np.int64)
    have = vals != np.iinfo(np.int64).min
    before = vals[have & (log_b < lo)][-LOG_MIN_FRAMES:]
    after = vals[have & (log_b > hi)][:LOG_MIN_FRAMES]
    if min(len(before), len(after)) < 1:
        return "no device status with clock_step_ns on both sides of the step"
    return Measured(float(np.median(after) - np.median(before)), 1e5, against)


def pick(sizes: list[int], measured: float, stderr: float) -> int | None:
    """The one candidate within the tolerance of a measured size, or None."""
    tol = min(LOG_TOLERANCE_NS, max(3e6, 4 * stderr))
    near = [c for c in sizes if abs(c - measured) <= tol]
    return near[0] if len(near) == 1 else None


def _describe(sizes: list[int]) -> str:
    return ", ".join(f"{c / 1e6:+.1f} ms ({lost} lost)" for lost, c in enumerate(sizes))


def size_by_log_times(st: "trig.Step", sizes: list[int], measures: list[tuple[Measured | str, int]]) -> int | None:
    """Choose ``st``'s size from log-time measurements against other streams, each ``(measurement or why not,
    the other stream's own step there)``; sets ``st.candidates_ns`` and, when none decides, ``st.evidence``.
    Returns the size, or None. Measurements that pick different candidates decide nothing."""
    st.candidates_ns = sizes
    picks, why = {}, []
    for m, other_step in measures:
        if isinstance(m, str):
            why.append(m)
            continue
        size = m.step_ns + other_step
        c = pick(sizes, size, m.stderr_ns)
        if c is None:
            why.append(f"{m.against} gives {size / 1e6:+.1f} +- {m.stderr_ns / 1e6:.1f} ms, "
                       f"not within {LOG_TOLERANCE_NS / 1e6:.1f} ms of exactly one candidate")
        else:
            picks[m.against] = (c, size, m.stderr_ns)
    chosen = {c for c, _, _ in picks.values()}
    if len(chosen) == 1:
        (c,) = chosen
        st.evidence = "; ".join(f"{o}: {s / 1e6:+.1f} +- {e / 1e6:.1f} ms" for o, (_, s, e) in picks.items()) + \
            f"; candidates {_describe(sizes)}"
        st.sized_by = "device status" if all(o.endswith("clock_step_ns") for o in picks) else \
            ("log times" if not any(o.endswith("clock_step_ns") for o in picks) else "log times and device status")
        return c
    if len(chosen) > 1:
        why.append("the log times against " + " and ".join(picks) + " pick different candidates")
    st.evidence = ("the IMU not recorded or silent; "
                   + ("; ".join(dict.fromkeys(why)) or "no other stream to compare log times with"))
    return None


def hidden_steps(t: np.ndarray, log: np.ndarray, found: list, others: list[tuple[np.ndarray, np.ndarray, list]],
                 period_ns: float) -> list:
    """Forward steps of a whole number of periods, which the stamps cannot see (the interval that holds one looks
    like frames lost on the host), found where ``log - stamp`` of this stream changes level against every other
    stream given (``(stamps, log times, its steps)``) by at least half a period, at an interval of two periods or
    more, away from the steps already ``found`` on this stream and those of the other streams. Returned as :class:`.trigger.Step` of the stamps' size (about 0), to be
    sized like any other (:func:`size_by_log_times`)."""
    u = log.astype(np.int64) - t.astype(np.int64)
    n, per_other = len(t), []
    if n < 2 * LOG_WINDOW + 1 or not others:
        return []
    theirs = [int(lb[st.index]) for tb, lb, steps in others for st in steps]
    for tb, lb, _ in others:
        ub = lb.astype(np.int64) - tb.astype(np.int64)
        if len(ub) < LOG_MIN_FRAMES:
            return []
        order = np.argsort(lb, kind="stable")
        j = np.clip(np.searchsorted(lb[order], log), 0, len(order) - 1)
        rel = (u - ub[order][j]).astype(float)
        per_other.append({st.index for st in trig.find_steps(rel, np.zeros(n, np.int64), period_ns,
                                                               window=LOG_WINDOW, min_ns=period_ns / 2)})
    k = trig.local_indices(t, period_ns)
    d = np.diff(t.astype(np.int64))
    out = []
    for i in sorted(per_other[0]):
        if not all(any(abs(i - x) <= LOG_GUARD + 1 for x in seen) for seen in per_other[1:]):
            continue        # not against every other stream: that stream's latency or clock changed, not this one's
        if any(abs(i - st.index) <= LOG_WINDOW for st in found) or \
                any(abs(int(log[i]) - x) <= (LOG_WINDOW + LOG_GUARD) * period_ns for x in theirs):
            continue
        lo, hi = max(1, i - LOG_GUARD - 1), min(n - 1, i + LOG_GUARD + 1)
        at = lo + int(np.argmax(d[lo - 1:hi]))          # the interval holding it: the longest nearby
        if d[at - 1] < 1.5 * period_ns:
            continue
        r = (t - t[0] - k * period_ns).astype(float)
        size = float(np.median(r[at:at + trig.STEP_WINDOW]) - np.median(r[max(0, at - trig.STEP_WINDOW):at]))
        out.append(trig.Step(at, int(t[at]), int(round(size)), exact=False))
    return out


def size_reference_steps(ref: "trig.CameraTriggers", tz: np.ndarray, lz: np.ndarray, others: dict,
                         period_ns: float, device: dict | None = None) -> None:
    """Size the ZED left's steps still known modulo a period, from the log times against every other stream
    given: ``others`` maps a stream name to ``(stamps, log times, its own steps)``; a stream that stepped at the
    same instant by a size not known exactly is not compared. Steps of whole periods the stamps cannot see are
    looked for first (:func:`hidden_steps`). ``device``: stream -> {frame stamp: clock_step_ns} from the device's
    status messages (:func:`device_status_step`). Updates ``ref`` (its steps, trigger numbering and residuals)."""
    hidden = hidden_steps(tz, lz, ref.steps, list(others.values()), period_ns)
    if hidden:
        ref.steps[:] = sorted(ref.steps + hidden, key=lambda st: st.index)
    for st in ref.steps:
        if st.exact:
            continue
        passed = int(ref.trigger[st.index] - ref.trigger[st.index - 1])
        sizes = candidates(st, passed, period_ns)
        measures = []
        for name, (ts, ls, own) in others.items():
            there = [o for o in own if abs(int(ls[o.index]) - int(lz[st.index])) < 3 * period_ns]
            if there and not there[0].exact:
                measures.append((f"{name} stepped there too by a size known modulo a period", 0))
                continue
            measures.append((log_time_step(tz, lz, st.index, ts, ls, period_ns, name),
                             there[0].step_ns if there else 0))
            if (device or {}).get(name):
                measures.append((device_status_step(lz, st.index, ts, ls, device[name], period_ns,
                                                    f"{name}'s device status clock_step_ns"),
                                 there[0].step_ns if there else 0))
        size = size_by_log_times(st, sizes, measures)
        if size is not None and (st not in hidden or abs(size) >= trig.STEP_MIN_NS):
            trig.size_step(ref, tz, st, size, st.sized_by, st.evidence, period_ns)
        elif st in hidden:          # a level change of the log times that sizes to no candidate: not a step
            ref.steps.remove(st)


def thermal_sizer(ts: np.ndarray, ls: np.ndarray, ref: "trig.CameraTriggers", tz: np.ndarray, lz: np.ndarray,
                  period_ns: float):
    """The ``size_steps`` hook of :func:`.trigger.assign` for one thermal camera: its own steps known modulo a
    period sized from the log times against the ZED left (whose step at the same instant, if any, must be
    known exactly)."""
    def size(own: list) -> None:
        k = trig.local_indices(ts, period_ns)
        hidden = hidden_steps(ts, ls, own, [(tz, lz, ref.steps)], period_ns)
        if hidden:
            own[:] = sorted(own + hidden, key=lambda st: st.index)
        for st in list(own):
            if st.exact:
                continue
            sizes = candidates(st, int(k[st.index] - k[st.index - 1]), period_ns)
            there = [z for z in ref.steps if abs(int(lz[z.index]) - int(ls[st.index])) < 3 * period_ns]
            if there and not there[0].exact:
                # both clocks stepped, neither size known: their difference, from the log times, says whether it is
                # one step (the sizes then cancel in the pairing: trigger.assign), written as the ZED's wrapped size
                st.candidates_ns = sizes
                z, m = there[0], log_time_step(ts, ls, st.index, tz, lz, period_ns, "zed_left")
                if not isinstance(m, str):
                    size = st.step_ns + round((z.step_ns + m.step_ns - st.step_ns) / period_ns) * period_ns
                    if abs(m.step_ns) <= min(LOG_TOLERANCE_NS, max(3e6, 4 * m.stderr_ns)):
                        st.step_ns = int(round(size))
                        st.evidence = (f"the ZED clock's step at the same instant: log - stamp against zed_left "
                                       f"{m.step_ns / 1e6:+.1f} +- {m.stderr_ns / 1e6:.1f} ms apart")
                        continue
                st.evidence = "the ZED clock stepped at the same instant, by a size known modulo a period"
                continue
            m = log_time_step(ts, ls, st.index, tz, lz, period_ns, "zed_left")
            c = size_by_log_times(st, sizes, [(m, there[0].step_ns if there else 0)])
            if c is not None and (st not in hidden or abs(c) >= trig.STEP_MIN_NS):
                st.step_ns, st.exact = c, True
            elif st in hidden:
                own.remove(st)
    return size


#: intervals under this share of a period, in a stream's recording order, are not frames one trigger apart
SHORT_INTERVAL = 0.25
#: two such intervals within this many frames are not one backward step: the frames are out of order
DISORDER_FRAMES = 10


def out_of_order(t: np.ndarray, period_ns: float) -> int | None:
    """The first frame of a stream whose recording order is not its arrival order, or None. A backward clock step
    leaves one short (or negative) interval; frames sorted by log times that went back (a recorder's clock stepped
    backward, or log times copied from stamps that did) interleave, leaving several within a few frames."""
    short = np.nonzero(np.diff(t.astype(np.int64)) < SHORT_INTERVAL * period_ns)[0]
    close = np.nonzero(np.diff(short) < DISORDER_FRAMES)[0]
    return int(short[close[0]] + 1) if len(close) else None


# ----------------------------------------------------------------------------- the steps of a recording
def corrected(stamps: np.ndarray, steps: list) -> np.ndarray:
    """One stream's stamps with its own clock steps taken out (each step's size subtracted from the frames from
    its index on, in recording order): the stamps on that stream's clock as it was before its first step."""
    out = stamps.astype(np.int64).copy()
    for st in steps:
        out[st.index:] -= int(st.step_ns)
    return out


def follow(stamps: np.ndarray, log_ns: np.ndarray, ref_stamps: np.ndarray, ref_log_ns: np.ndarray,
           ref_corrected: np.ndarray, period_ns: float) -> np.ndarray:
    """A stream on the same clock as a reference (the ZED right and depth: the same grab as the ZED left)
    corrected as the reference is: each frame by its reference frame of the same stamp (the one logged nearest,
    when a backward step gave two frames one stamp), else by the reference frame logged nearest."""
    t = stamps.astype(np.int64)
    if len(ref_stamps) == 0:
        return t.copy()
    shift = ref_stamps.astype(np.int64) - ref_corrected
    same: dict[int, list[int]] = {}
    for i, x in enumerate(ref_stamps.tolist()):
        same.setdefault(int(x), []).append(i)
    order = np.argsort(ref_log_ns, kind="stable")
    logs = ref_log_ns[order]
    j = np.clip(np.searchsorted(logs, log_ns), 1, max(len(logs) - 1, 1))
    if len(logs) > 1:
        j = np.where(np.abs(logs[j - 1] - log_ns) <= np.abs(logs[j] - log_ns), j - 1, j)
    nearest = order[np.minimum(j, len(logs) - 1)]
    pick = []
    for x, lg, n in zip(t, log_ns, nearest):
        i = min(same.get(int(x), [int(n)]), key=lambda i: abs(int(ref_log_ns[i]) - int(lg)))
        # the same stamp logged half a period away is another grab (a backward step of whole periods)
        pick.append(i if abs(int(ref_log_ns[i]) - int(lg)) < period_ns / 2 else int(n))
    return t - shift[np.array(pick, np.int64)]


def step_dict(st) -> dict:
    """A step as the reports give it."""
    return {"at_ns": int(st.at_ns), "step_ms": st.step_ns / 1e6, "exact": bool(st.exact), "sized_by": st.sized_by,
            "candidates_ms": [c / 1e6 for c in st.candidates_ns], "evidence": st.evidence}


def events(per_stream: dict, imu_steps: list[dict], period_ns: float) -> list[dict]:
    """The clock steps of a recording as events: steps of several streams at one instant (their log times within
    3 periods) are one event, which names its clocks. ``per_stream``: stream -> (its steps, its log times);
    ``imu_steps``: :func:`.sync.find_clock_steps` on the IMU, whose instant (200 Hz) is kept when it matches the
    ZED's step. Each event: ``at_ns`` (first stamp after, on the first clock listed), ``step_ns`` (that clock's
    step), ``found_on``, ``clocks`` (stream -> :func:`step_dict`)."""
    flat = sorted(((int(log[st.index]), name, st) for name, (steps, log) in per_stream.items() for st in steps),
                  key=lambda x: x[0])
    out, last = [], None
    for when, name, st in flat:
        if last is None or when - last > 3 * period_ns:
            out.append({"at_ns": int(st.at_ns), "step_ns": int(st.step_ns), "found_on": name, "clocks": {}})
        out[-1]["clocks"][name] = step_dict(st)
        last = when
    for ev in out:
        z = ev["clocks"].get("zed_left")
        if z is None:
            continue
        ev["at_ns"], ev["step_ns"], ev["found_on"] = z["at_ns"], int(round(z["step_ms"] * 1e6)), "zed_left"
        for s in imu_steps:
            if s.get("found_on") == "zed_imu" and abs(s["at_ns"] - z["at_ns"]) < 2 * period_ns \
                    and abs(s["step_ns"] - ev["step_ns"]) < 3e6:
                ev["at_ns"], ev["found_on"] = s["at_ns"], "zed_imu"
    return out
