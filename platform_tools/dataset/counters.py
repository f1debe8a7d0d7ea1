"""The Boson's telemetry frame counter as pairing evidence.

In external-sync slave mode a Boson outputs one frame per trigger pulse it receives, and the frame counter
of its telemetry line (:mod:`platform_tools.boson.telemetry`: a u32 at byte 84) counts them. Between two
frames the host received, the counter advanced by ``dc`` while the stamps advanced by ``m`` periods
(``round(interval / period)``):

- ``dc == m``: every pulse came; ``dc - 1`` frames were lost on the way to the host (*host drops*: the ZED
  saw those pulses, so they say nothing about the offset);
- ``dc < m``: ``m - dc`` pulses never reached the camera (*missing pulses*: when the pulse was missing at its
  source, the ZED has a hole at the same trigger: an *anchor* that pins the offset);
- ``dc == 0``: a repeated frame (the counter did not advance).

Across a clock step of the thermal stream the stamps lie and the counter does not: indexed by the counter,
the stamps less their trigger grid change level by the step's full size (either sign, any size, no
modulo-one-period ambiguity), and by a whole number of periods where pulses went missing. A level change
within :data:`PULSE_TOLERANCE_NS` of a positive multiple of the period is missing pulses, any other one a
clock step. Two limits follow: a thermal clock step of a whole number of periods (within that tolerance)
is read as missing pulses, and a pulse missing in the very interval that holds a step makes the step one
period larger than it was.

Pure functions over numpy arrays; no I/O.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: the counter is a u32 (telemetry.FRAME_COUNTER_OFFSET): differences are taken modulo this
COUNTER_MODULO = 1 << 32
#: a level change (medians of a few frames) this close to a positive multiple of the period is missing
#: pulses, not a clock step
PULSE_TOLERANCE_NS = 1_500_000
#: the counter is read only when it advances as the stamps do (dc == m) over at least this share of the
#: intervals: a counter decoded from the wrong bytes (telemetry.py's layout is still to be checked on a camera)
#: must never steer the pairing
MIN_AGREEMENT = 0.9
#: one interval this close to a positive multiple of the period more than the counter says holds missing
#: pulses (a single interval carries two stamps' jitter, about 0.85 ms for a Boson)
INTERVAL_TOLERANCE_NS = 4_000_000


@dataclass(frozen=True)
class Gaps:
    """What the counter says of every gap between frames the host received."""
    host_drops: int             # frames the camera counted that never reached the recording
    missing_pulses: int         # trigger pulses the camera never received
    repeated: int               # frames whose counter did not advance
    missing: np.ndarray         # int per frame: pulses that never came in the gap before it (0: none, or the
                                # interval of a clock step, whose stamps are not read)
    anchor: np.ndarray          # bool per frame: that gap holds missing pulses and nothing else (every trigger
                                # in it is a pulse the camera never got)


def steps_of(counter: np.ndarray) -> np.ndarray:
    """Counter increments between consecutive frames (int64, modulo 2**32: the counter wraps)."""
    return np.mod(np.diff(counter.astype(np.int64)), COUNTER_MODULO)


def pulse_index(counter: np.ndarray) -> np.ndarray:
    """Each frame's pulse count since the first frame, from the counter alone (a repeat counts one)."""
    return np.concatenate([[0], np.cumsum(np.maximum(1, steps_of(counter)))])


def classify(ts: np.ndarray, counter: np.ndarray, period_ns: float,
             step_intervals: set[int] = frozenset()) -> Gaps:
    """Host drops, missing pulses and repeats between consecutive frames. ``step_intervals``: the frames that
    follow a clock step of this stream (the stamps of the interval before them lie: it is not read)."""
    dc = steps_of(counter)
    m = np.maximum(1, np.round(np.diff(ts.astype(np.int64)) / period_ns).astype(np.int64))
    read = np.ones(len(dc), bool)
    for i in step_intervals:
        if 0 < i <= len(dc):
            read[i - 1] = False
    missing = np.where(read & (dc > 0), np.maximum(m - dc, 0), 0)
    anchor = np.concatenate([[False], (missing > 0) & (dc == 1)])
    return Gaps(host_drops=int(np.sum(np.maximum(dc - 1, 0))), missing_pulses=int(missing.sum()),
                repeated=int(np.sum(dc == 0)), missing=np.concatenate([[0], missing]), anchor=anchor)


def pulse_grid_index(ts: np.ndarray, counter: np.ndarray, period_ns: float) -> np.ndarray:
    """Each frame's trigger count since the first: the counter's increments, plus the pulses that never came
    where an interval is a whole number of periods longer than the counter says (within
    :data:`INTERVAL_TOLERANCE_NS`). Indexed so, the stamps less ``index * period`` are flat but for jitter
    and the clock steps, at their full size."""
    dc = np.maximum(1, steps_of(counter))
    e = np.diff(ts.astype(np.int64)) - dc * period_ns
    j = np.round(e / period_ns)
    missing = np.where((j >= 1) & (np.abs(e - j * period_ns) < INTERVAL_TOLERANCE_NS), j, 0).astype(np.int64)
    return np.concatenate([[0], np.cumsum(dc + missing)])


def is_missing_pulses(level_change_ns: float, period_ns: float) -> bool:
    """Whether a level change of the counter-indexed stamps is pulses that never came (a positive whole
    number of periods) rather than a clock step."""
    j = round(level_change_ns / period_ns)
    return j >= 1 and abs(level_change_ns - j * period_ns) < PULSE_TOLERANCE_NS


def implausible(ts: np.ndarray, counter: np.ndarray, period_ns: float) -> str | None:
    """Why this counter cannot be the Boson's frame counter (one phrase), or None when it advances as the
    stamps do over at least :data:`MIN_AGREEMENT` of the intervals."""
    if len(counter) < 3:
        return "fewer than 3 frames"
    dc = steps_of(counter)
    m = np.maximum(1, np.round(np.diff(ts.astype(np.int64)) / period_ns).astype(np.int64))
    share = float(np.mean(dc == m))
    if share < MIN_AGREEMENT:
        return (f"it advances as the stamps do on only {100 * share:.0f} % of the intervals (median step "
                f"{int(np.median(dc))}); check the telemetry layout (platform_tools/boson/telemetry.py)")
    return None
