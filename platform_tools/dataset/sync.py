"""Sync analysis of a recording: can its frames be trusted to pair?

All times are the header stamps the drivers wrote (host clock). In order:

1. Clock steps, per stream: the host clock jumping (NTP, a manual set) shows as a gap, or a negative
   interval, in the streams whose stamps follow it (the ZED's; usb_cam's Boson stamps do not). Each
   stream's own steps are found on its stamps (:mod:`.trigger`) and sized by the IMU, the frame counter,
   the recorder's log times or the device's status (:mod:`.clocksteps`); each stream's stamps lose its
   own steps before anything else is computed. ``find_clock_steps`` (the IMU, or a gap common to every
   camera) remains for the IMU's own statistics, the instant of an IMU-sized step, and a recording whose
   steps cannot be read per stream.
2. Per stream: intervals (mean, std, min, max), drops (an interval above ``drop_interval_factor`` x
   the nominal period; missing frames = round(interval / period) - 1), and the per-frame jitter
   (std of the intervals that are one period, / sqrt 2: each interval is the difference of two stamps).
3. FFC periods per thermal camera: from the status topic (ffc_status 2 = in progress), else from the
   same state in the Boson telemetry rows of each frame, else from frozen frames (image pixels
   identical to the previous frame).
4. Pairing residuals for the thermal pair and ZED left to each thermal camera: each frame of the
   second stream against the nearest frame of the first (within half a period); mean, std, p99, max;
   a line fit over time gives the constant offset and the drift in ppm (with its standard error);
   the verdict judges the jitter about that line (p99 of |residual - fit|) and the drift, beyond
   three standard errors (a short recording's jitter alone makes a slope of tens of ppm).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import logging

from .recording import CAMERAS, Recording, RecordingError
from . import clocksteps, counters, ffcstatus, motion, trigger as trig

log = logging.getLogger(__name__)

NS = 1_000_000_000
PAIRS = (("thermal_left", "thermal_right"), ("zed_left", "thermal_left"), ("zed_left", "thermal_right"))


@dataclass(frozen=True)
class Limits:
    drop_interval_factor: float
    max_drop_percent: float
    max_pair_jitter_p99_ms: float
    max_drift_ppm: float

    @classmethod
    def from_rig(cls, rig, **overrides) -> "Limits":
        lim = rig.desc.processing.sync_limits
        values = dict(drop_interval_factor=lim.drop_interval_factor, max_drop_percent=lim.max_drop_percent,
                      max_pair_jitter_p99_ms=lim.max_pair_jitter_p99_ms, max_drift_ppm=lim.max_drift_ppm)
        values.update({k: v for k, v in overrides.items() if v is not None})
        return cls(**values)


def _stats_ms(x_ns: np.ndarray) -> dict:
    if len(x_ns) == 0:
        return {"mean": None, "std": None, "min": None, "max": None}
    x = x_ns / 1e6
    return {"mean": float(np.mean(x)), "std": float(np.std(x)), "min": float(np.min(x)), "max": float(np.max(x))}


def find_clock_steps(rec: Recording, period_ns: float) -> list[dict]:
    """Steps of the host clock: [{at_ns (first stamp after, as recorded), step_ns}]."""
    if rec.has("zed_imu") and len(rec.streams["zed_imu"].stamp_ns) > 10:
        t = rec.streams["zed_imu"].stamp_ns
        d = np.diff(t)
        med = float(np.median(d))
        idx = np.nonzero((d > 10 * med) | (d < 0))[0]
        return [{"at_ns": int(t[i + 1]), "step_ns": int(d[i] - med), "found_on": "zed_imu"} for i in idx]
    # no IMU: a gap in every camera at the same instant
    cams = [c for c in CAMERAS if rec.has(c)]
    if len(cams) < 2:
        return []
    gaps = {}
    for c in cams:
        t = rec.streams[c].stamp_ns
        d = np.diff(t)
        big = np.nonzero((d > 3 * period_ns) | (d < 0))[0]
        gaps[c] = [(int(t[i + 1]), int(d[i])) for i in big]
    steps = []
    for at, d in gaps[cams[0]]:
        matched = [min(gaps[c], key=lambda g: abs(g[0] - at), default=None) for c in cams[1:]]
        if all(m is not None and abs(m[0] - at) < 1.5 * period_ns for m in matched):
            # the smallest gap excess over one period among the cameras is the step (the others add drops)
            excess = [d - period_ns] + [m[1] - period_ns for m in matched]
            steps.append({"at_ns": at, "step_ns": int(min(excess, key=abs)), "found_on": "cameras"})
    return steps


def corrected(stamps: np.ndarray, steps: list[dict]) -> np.ndarray:
    """Stamps with the clock steps taken out (each step subtracted from the stamps after it)."""
    out = stamps.astype(np.int64).copy()
    for s in steps:
        # the step happened between two messages of every stream; recorded stamps after it are >= at_ns
        # when the step is forward; a backward step is found by the order of the recording instead
        if s["step_ns"] >= 0:
            out[stamps >= s["at_ns"]] -= s["step_ns"]
        else:
            d = np.diff(stamps)
            neg = np.nonzero(d < 0)[0]
            if len(neg):
                out[neg[0] + 1:] -= s["step_ns"]
    return out


def stream_report(t: np.ndarray, period_ns: float, factor: float) -> dict:
    d = np.diff(np.sort(t))
    drop = d > factor * period_ns
    missing = np.maximum(np.round(d[drop] / period_ns).astype(int) - 1, 0)
    one = d[np.abs(d - period_ns) < 0.5 * period_ns]
    expected = len(t) + int(missing.sum())
    return {"frames": int(len(t)), "interval_ms": _stats_ms(d),
            "jitter_ms": float(np.std(one) / np.sqrt(2) / 1e6) if len(one) > 2 else None,
            "drops": {"events": int(drop.sum()), "missing_frames": int(missing.sum()),
                      "percent": 100.0 * int(missing.sum()) / max(expected, 1),
                      "at_ns": [int(x) for x in np.sort(t)[1:][drop]]}}


def ffc_periods(rec: Recording, camera: str, period_ns: float) -> list[dict]:
    """FFC periods of a thermal camera (host stamps): from its status topic, else from the telemetry
    rows of its frames (``rec.status`` holds either, ``rec.status_source`` says which), else from
    frozen frames."""
    status = rec.status.get(camera) or []
    source = (getattr(rec, "status_source", None) or {}).get(camera) or "status"
    lag = (getattr(rec, "status_lag_frames", None) or {}).get(camera, 0)
    if lag:
        source += f" (moved {lag:+d} trigger{'s' if abs(lag) > 1 else ''} onto the FFC freeze)"
    out = []
    if status:
        start = None
        for stamp, state in sorted(status):
            if state == 2 and start is None:
                start = stamp
            elif state != 2 and start is not None:
                out.append({"start_ns": start, "end_ns": stamp, "source": source})
                start = None
        if start is not None:
            out.append({"start_ns": start, "end_ns": int(rec.streams[camera].stamp_ns.max()), "source": source})
        return out
    s = rec.streams.get(camera)
    if s is None or s.frozen is None:
        return out
    t, fr = s.stamp_ns, s.frozen
    i = 0
    while i < len(t):
        if fr[i]:
            j = i
            while j + 1 < len(t) and fr[j + 1]:
                j += 1
            if j - i + 1 >= 3:   # a few identical frames in a row: noise never repeats exactly
                out.append({"start_ns": int(t[i - 1] if i else t[i]), "end_ns": int(t[j] + period_ns),
                            "source": "frozen frames"})
            i = j + 1
        else:
            i += 1
    return out


def pair_residuals(ta: np.ndarray, tb: np.ndarray, period_ns: float) -> tuple[np.ndarray, np.ndarray]:
    """(time, residual tb - nearest ta) for every b frame with an a frame within half a period."""
    ta = np.sort(ta)
    tb = np.sort(tb)
    if len(ta) == 0 or len(tb) == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    i = np.clip(np.searchsorted(ta, tb), 1, len(ta) - 1) if len(ta) > 1 else np.zeros(len(tb), int)
    cand = np.stack([ta[np.maximum(i - 1, 0)], ta[i]])
    best = cand[np.argmin(np.abs(cand - tb), axis=0), np.arange(len(tb))]
    r = tb - best
    # pairing is by trigger: the residual's typical value (a constant offset) may be up to half a period
    ok = np.abs(r) < period_ns / 2
    return tb[ok], r[ok]


def pair_report(t: np.ndarray, r_ns: np.ndarray) -> dict:
    if len(r_ns) < 3:
        return {"pairs": int(len(r_ns)), "residual_ms": None, "offset_ms": None, "drift_ppm": None,
                "jitter_p99_ms": None}
    r = r_ns / 1e6
    x = (t - t[0]) / NS
    slope, intercept = np.polyfit(x, r, 1)            # ms per s -> ppm: x 1000
    fit = intercept + slope * x
    se = np.sqrt(np.sum((r - fit) ** 2) / max(len(r) - 2, 1) / max(np.sum((x - x.mean()) ** 2), 1e-12))
    return {"pairs": int(len(r)),
            "residual_ms": {"mean": float(np.mean(r)), "std": float(np.std(r)),
                            "p99": float(np.percentile(np.abs(r), 99)), "max": float(np.max(np.abs(r)))},
            "offset_ms": float(np.median(r)), "drift_ppm": float(slope * 1000.0),
            "drift_stderr_ppm": float(se * 1000.0),
            "jitter_p99_ms": float(np.percentile(np.abs(r - fit), 99))}


def analyse(rec: Recording, rig, limits: Limits) -> dict:
    rate = rig.desc.sync.rate_hz
    period = 1e9 / rate
    rec.require("thermal_left", "thermal_right", why="sync-check needs both thermal streams")
    steps = host_steps = find_clock_steps(rec, period)      # the host's steps (IMU, or common to every camera)
    # each stream's own clock steps (trigger.py, sized by clocksteps.py), taken out of that stream's stamps
    try:
        assignment, trig_err = triggers(rec, rig), None
        per = {"zed_left": assignment.reference.steps} | {c: ct.steps for c, ct in assignment.cameras.items()}
    except RecordingError as exc:
        assignment, trig_err = None, str(exc)
        try:
            prep, _, own = stream_steps(rec, rig)
            per = {"zed_left": prep.reference.steps} | own
        except RecordingError:
            per = None
    common = {n: corrected(rec.streams[n].stamp_ns, steps) for n in CAMERAS + ("zed_depth",) if rec.has(n)}
    times = common
    if per is not None:
        times = corrected_times(rec, per, CAMERAS + ("zed_depth",), period)
        events = clocksteps.events({n: (v, rec.streams[n].log_ns) for n, v in per.items()}, steps, period)
        # the nearest-stamp statistics: a step of every clock at once is one host step, taken out at one size (the
        # IMU's, or the cameras' common gap: a thermal size fitted from its segments would absorb a drift); a step
        # of some clocks only, per stream
        if not (steps and all(len(ev["clocks"]) == 3 for ev in events)):
            common = times
        steps = events
    streams = {}
    for name in CAMERAS + ("zed_depth",):
        if not rec.has(name):
            continue
        t = times[name]
        streams[name] = {"topic": rec.streams[name].topic} | stream_report(t, period, limits.drop_interval_factor)
    if rec.has("zed_imu"):
        t = corrected(rec.streams["zed_imu"].stamp_ns, host_steps)
        d = np.diff(t)
        streams["zed_imu"] = {"topic": rec.streams["zed_imu"].topic, "frames": int(len(t)),
                              "interval_ms": _stats_ms(d)}
    ffc = {c: ffc_periods(rec, c, period) for c in ("thermal_left", "thermal_right")}
    pairs, series = {}, {}
    for a, b in PAIRS:
        if a in common and b in common:
            t, r = pair_residuals(common[a], common[b], period)
            pairs[f"{a}-{b}"] = pair_report(t, r)
            series[f"{a}-{b}"] = (t, r)
    checks = []
    for name, s in streams.items():
        if "drops" in s:
            checks.append({"check": f"{name} drops", "value": round(s["drops"]["percent"], 3),
                           "limit": limits.max_drop_percent, "unit": "%",
                           "ok": s["drops"]["percent"] <= limits.max_drop_percent})
    for name, p in pairs.items():
        if p["jitter_p99_ms"] is None:
            checks.append({"check": f"{name} pairs", "value": p["pairs"], "limit": 3, "unit": "pairs", "ok": False})
            continue
        checks.append({"check": f"{name} jitter p99", "value": round(p["jitter_p99_ms"], 3),
                       "limit": limits.max_pair_jitter_p99_ms, "unit": "ms",
                       "ok": p["jitter_p99_ms"] <= limits.max_pair_jitter_p99_ms})
        # a drift fails when it is beyond the limit by more than its noise (3 standard errors): on a
        # short recording the jitter alone makes a slope of tens of ppm
        checks.append({"check": f"{name} drift", "value": round(p["drift_ppm"], 2),
                       "limit": limits.max_drift_ppm, "unit": "ppm",
                       "ok": abs(p["drift_ppm"]) - 3 * p["drift_stderr_ppm"] <= limits.max_drift_ppm})
    trig_rep = trigger_report(assignment) if assignment is not None else None
    checks.append({"check": "trigger of every thermal frame", "value": trig_err or "established",
                   "limit": "unambiguous", "unit": "", "ok": trig_err is None})
    by_trigger = {}
    if assignment is not None:
        # jitter and drift of frames of the same trigger, each stream's clock steps taken out (per segment)
        frames = {"zed_left": (rec.streams["zed_left"].stamp_ns, assignment.reference)} | {
            c: (rec.streams[c].stamp_ns, assignment.cameras[c]) for c in ("thermal_left", "thermal_right")}
        by_trigger = {f"{a}-{b}": trigger_pair_report(*frames[a], *frames[b]) for a, b in PAIRS}
        checks = [c for c in checks if not any(c["check"].startswith(name + " ") for name in by_trigger)]
        for name, p in by_trigger.items():
            checks.append({"check": f"{name} jitter p99", "value": round(p["jitter_p99_ms"], 3),
                           "limit": limits.max_pair_jitter_p99_ms, "unit": "ms",
                           "ok": p["jitter_p99_ms"] <= limits.max_pair_jitter_p99_ms})
            checks.append({"check": f"{name} drift", "value": round(p["drift_ppm"], 2),
                           "limit": limits.max_drift_ppm, "unit": "ppm",
                           "ok": abs(p["drift_ppm"]) - 3 * p["drift_stderr_ppm"] <= limits.max_drift_ppm})
    report = {"triggers": trig_rep, "recording": str(rec.path), "files": [str(f) for f in rec.files], "recovered": rec.recovered,
              "nominal_rate_hz": rate, "clock_steps": steps, "streams": streams, "ffc": ffc, "pairs": pairs,
              "pairs_by_trigger": by_trigger,
              "limits": limits.__dict__, "checks": checks,
              "verdict": "pass" if all(c["ok"] for c in checks) else "fail"}
    report["_series"] = series   # for the plots; removed before printing
    report["_times"] = times
    return report


def _segment_ids(n: int, ct: "trig.CameraTriggers", reference: bool) -> np.ndarray:
    """Per frame, which clock segment it is in (cut at every step of its stream)."""
    ids = np.zeros(n, np.int64)
    cuts = [s.index for s in ct.steps] if reference else [g.first for g in ct.segments[1:]]
    for c in sorted(cuts):
        ids[c:] += 1
    return ids


def trigger_pair_report(ta: np.ndarray, ca: "trig.CameraTriggers", tb: np.ndarray,
                        cb: "trig.CameraTriggers") -> dict:
    """Frames of two streams exposed by the same trigger: how their stamp difference varies (jitter p99 about
    the fit) and drifts (ppm, pooled within the segments between clock steps of either stream, so a step is
    never read as drift), with the drift's standard error."""
    ia = {int(k): i for i, k in enumerate(ca.trigger) if k >= 0}
    both = [(ia[int(k)], j) for j, k in enumerate(cb.trigger) if k >= 0 and int(k) in ia]
    if len(both) < 3:
        return {"pairs": len(both), "jitter_p99_ms": float("inf"), "drift_ppm": 0.0, "drift_stderr_ppm": float("inf")}
    i, j = np.array(both).T
    r = (tb[j].astype(np.int64) - ta[i].astype(np.int64)).astype(float) / 1e6        # ms
    x = (ta[i] - ta[i].min()).astype(float) / NS                                        # s
    group = _segment_ids(len(ta), ca, ca.camera == "zed_left")[i] * 1000 + \
        _segment_ids(len(tb), cb, cb.camera == "zed_left")[j]
    dx, dr = x.copy(), r.copy()
    for g in np.unique(group):
        m = group == g
        dx[m] -= dx[m].mean()
        dr[m] -= dr[m].mean()
    sxx = float(np.sum(dx ** 2))
    slope = float(np.sum(dx * dr) / sxx) if sxx > 0 else 0.0                            # ms per s
    res = dr - slope * dx
    dof = max(len(r) - 1 - len(np.unique(group)), 1)
    se = float(np.sqrt(np.sum(res ** 2) / dof / max(sxx, 1e-12)))
    return {"pairs": len(r), "segments": int(len(np.unique(group))),
            "jitter_p99_ms": float(np.percentile(np.abs(res), 99)),
            "drift_ppm": slope * 1000.0, "drift_stderr_ppm": se * 1000.0}


def triggers(rec: Recording, rig) -> "trig.Assignment":
    """Which trigger exposed every thermal frame (see :mod:`.trigger`; image motion, :mod:`.motion`, as the last
    resort; steps known modulo a period sized by :mod:`.clocksteps`); RecordingError when ambiguous."""
    period = 1e9 / rig.desc.sync.rate_hz
    zl = rec.streams["zed_left"]
    out, used, _ = stream_steps(rec, rig)
    ref = out.reference
    frames = motion.Reader(rec, rig)        # read only when the stamps leave a camera's offset ambiguous
    windows = rig.desc.sync.stamp_latency_ms
    for cam, counter in used.items():
        st = rec.streams[cam]
        w = windows.get(cam)
        try:
            out.cameras[cam] = trig.assign(zl.stamp_ns, st.stamp_ns, period, camera=cam, ref=ref,
                                           window_ms=(w.min.value, w.max.value) if w else None,
                                           counter=counter, where=f"{rec.path}: {st.topic}: ",
                                           motion=frames.resolver(cam, ref.trigger),
                                           size_steps=clocksteps.thermal_sizer(st.stamp_ns, st.log_ns, ref,
                                                                               zl.stamp_ns, zl.log_ns, period))
        except trig.TriggerError as exc:
            raise RecordingError(str(exc)) from None
    return out


def stream_steps(rec: Recording, rig) -> tuple["trig.Assignment", dict, dict]:
    """The clock steps of every stream before any pairing: (an Assignment holding the ZED left's reference, its
    steps sized where the evidence allows; thermal camera -> the frame counter used or None; thermal camera ->
    its own steps, sized likewise)."""
    period = 1e9 / rig.desc.sync.rate_hz
    zl = rec.streams["zed_left"]
    for name in ("zed_left", "thermal_left", "thermal_right"):
        s = rec.streams[name]
        i = clocksteps.out_of_order(s.stamp_ns, period)
        if i is not None:
            raise RecordingError(
                f"{rec.path}: {s.topic}: frames out of order from stamp {int(s.stamp_ns[i])} (several intervals under "
                f"a quarter period within {clocksteps.DISORDER_FRAMES} frames): the log times went back (a "
                f"recorder clock stepped backward, or log times copied from stamps that did), and this reader "
                f"orders messages by log time; missing evidence: the arrival order")
    imu = rec.streams["zed_imu"].stamp_ns if rec.has("zed_imu") else None
    ref = trig.reference(zl.stamp_ns, period, imu)
    out = trig.Assignment(period, ref)
    used = {}
    for cam in ("thermal_left", "thermal_right"):
        st = rec.streams[cam]
        counter = getattr(st, "counter", None)
        why = counters.implausible(st.stamp_ns, counter, period) if counter is not None else None
        if why:
            out.ignored_counters[cam] = f"{st.topic}: the telemetry frame counter is not used: {why}"
            log.warning("%s: %s", rec.path, out.ignored_counters[cam])
            counter = None
        used[cam] = counter
    own = {}
    for cam, c in used.items():
        t = rec.streams[cam].stamp_ns
        own[cam] = trig.counter_steps(t, c, period) if c is not None else \
            trig.find_steps(t, trig.local_indices(t, period), period)
    # the ZED's steps known modulo a period, sized by the log times against each Boson (clocksteps.py), then each
    # Boson's against the ZED
    clocksteps.size_reference_steps(ref, zl.stamp_ns, zl.log_ns, {
        cam: (rec.streams[cam].stamp_ns, rec.streams[cam].log_ns, own[cam]) for cam in used}, period,
        device=device_clock_steps(rec))
    for cam in used:
        st = rec.streams[cam]
        clocksteps.thermal_sizer(st.stamp_ns, st.log_ns, ref, zl.stamp_ns, zl.log_ns, period)(own[cam])
    return out, used, own


def device_clock_steps(rec: Recording) -> dict[str, dict[int, int]]:
    """Per thermal camera: frame stamp -> ``clock_step_ns`` (the host clock's steps since usb_cam started, as the
    device's FFC status node publishes them in each frame's DiagnosticArray, header stamp = the frame's), from its
    status topic; empty when the recording has no such values (another node, a Bool status, none). The index
    (recording.open_recording) reads them in its one pass over the file; a Recording without them
    (``clock_step_values`` None) has its status topics read here."""
    if rec.clock_step_values is not None:
        return {c: dict(v) for c, v in rec.clock_step_values.items() if v}
    from mcap.exceptions import McapError
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    topics = {rec._topics.get(f"{c}_status"): c for c in ("thermal_left", "thermal_right")}
    topics.pop(None, None)
    out: dict[str, dict[int, int]] = {c: {} for c in topics.values()}
    decoder, decoders = DecoderFactory(), {}
    for fi, f in enumerate(rec.files):
        try:
            with open(f, "rb") as fh:
                for schema, channel, msg in make_reader(fh).iter_messages(topics=list(topics)):
                    if not schema or not schema.name.endswith("DiagnosticArray"):
                        continue
                    dec = decoders.get((fi, schema.id)) or decoders.setdefault((fi, schema.id),
                                                                                 decoder.decoder_for("cdr", schema))
                    out[topics[channel.topic]].update(ffcstatus.clock_step_values(dec(msg.data)))
        except (McapError, EOFError, ValueError) as exc:
            raise RecordingError(f"{f}: damaged MCAP ({type(exc).__name__}: {exc})") from None
    return {c: v for c, v in out.items() if v}


def corrected_times(rec: Recording, steps: dict, names, period_ns: float) -> dict[str, np.ndarray]:
    """Per stream, its stamps with its own clock's steps taken out (``steps``: zed_left / thermal camera -> its
    steps); the ZED right and depth follow the ZED left (the same grab)."""
    zl = rec.streams["zed_left"]
    out = {"zed_left": clocksteps.corrected(zl.stamp_ns, steps["zed_left"])}
    for name in names:
        if name in out or not rec.has(name):
            continue
        s = rec.streams[name]
        out[name] = clocksteps.corrected(s.stamp_ns, steps[name]) if name in steps else \
            clocksteps.follow(s.stamp_ns, s.log_ns, zl.stamp_ns, zl.log_ns, out["zed_left"], period_ns)
    return out


def trigger_report(a: "trig.Assignment") -> dict:
    """Per camera: offset after the ZED (per segment), its uncertainty, how it was established, steps."""
    def steps(ct):
        return [{"at_ns": s.at_ns, "step_ms": s.step_ns / 1e6, "exact": s.exact, "sized_by": s.sized_by,
                 "candidates_ms": [c / 1e6 for c in s.candidates_ns], "evidence": s.evidence} for s in ct.steps]
    out = {"zed_left": {"clock_steps": steps(a.reference)}}
    for cam, ct in a.cameras.items():
        out[cam] = {"segments": [{"frames": [g.first, g.last], "offset_ms": g.offset_ns / 1e6,
                                  "uncertainty_ms": g.uncertainty_ns / 1e6, "established_by": g.established_by,
                                  "candidates_ms": g.candidates_ms, "motion": g.motion} for g in ct.segments],
                    "clock_steps": steps(ct), "unassigned_frames": int((ct.trigger < 0).sum()),
                    "jitter_ms": ct.jitter_ns / 1e6,
                    "frame_counter": ({"host_drops": ct.host_drops, "missing_pulses": ct.missing_pulses,
                                       "repeated_frames": ct.repeated} if ct.counter else
                                      ({"ignored": a.ignored_counters[cam]} if cam in a.ignored_counters else None))}
    return out
