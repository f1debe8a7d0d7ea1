"""A thermal camera's FFC status messages to ``(host stamp ns, ffc_status)`` rows (2: FFC in progress, 0: not).

Two message types are read (the released TartanRGBT stack does not publish which type its ``ffc_status`` is):

- ``diagnostic_msgs/msg/DiagnosticArray``, as this project's FFC status node publishes it: a status whose values
  hold the key ``ffc_status``; the stamp is the array's header stamp;
- ``std_msgs/msg/Bool``: true during an FFC. A Bool has no header: its row is stamped with the header stamp of the
  camera's latest frame logged before it (the status is published per frame, after it), or with its own log
  time when no frame came yet.

Any other type is refused (:class:`StatusTypeError`, one line); a recording without status messages falls back
to the Boson telemetry rows, then to frozen frames (:mod:`.recording`, :mod:`.sync`).

**The FFC freeze as evidence of the status's frame**: a status stamped by a frame may belong to another one (a Bool
logged before its image reaches the recorder is stamped with the frame before; a camera's telemetry may flag the
FFC a frame before its image freezes). The freeze (frames whose image repeats, a known span) is in the frames
themselves: :func:`frame_lag` finds the shift of the in-progress rows that lays them on it, :func:`shifted` applies
it. (The ZED does not see an FFC: the freeze says nothing of a Boson's trigger offset against the ZED.)
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

BOOL = "std_msgs/msg/Bool"
DIAGNOSTIC = "diagnostic_msgs/msg/DiagnosticArray"
ACCEPTED = (BOOL, DIAGNOSTIC)


class StatusTypeError(Exception):
    """A status topic of a type this reader does not know; one line (without the file and topic)."""


def normalise(schema_name: str) -> str:
    """``pkg/msg/Type`` for ``pkg/msg/Type`` or ``pkg/Type``."""
    parts = schema_name.split("/")
    return f"{parts[0]}/msg/{parts[1]}" if len(parts) == 2 else schema_name


def check_type(schema_name: str) -> str:
    """The normalised type, or :class:`StatusTypeError` when it is not one of :data:`ACCEPTED`."""
    t = normalise(schema_name)
    if t not in ACCEPTED:
        raise StatusTypeError(f"FFC status of type {schema_name or '(none)'}; expected {' or '.join(ACCEPTED)} "
                              f"(true during FFC); leave the status topic out of a --topics map to detect FFC "
                              f"from frozen frames instead")
    return t


def decode(type_name: str, data):
    """One CDR-serialised status message of type ``type_name`` (:func:`check_type`'s), read by :mod:`.cdr` (the
    fields :func:`rows` and :func:`clock_step_values` read, as mcap_ros2's decoder gives them); ValueError when it is
    cut short."""
    from .cdr import bool_message, diagnostic_array
    return bool_message(data) if type_name == BOOL else diagnostic_array(data)


def rows(type_name: str, msg, log_ns: int, last_frame_stamp: int | None) -> list[tuple[int, int]]:
    """The ``(stamp ns, ffc_status)`` rows of one decoded status message of type ``type_name``
    (:func:`check_type`'s)."""
    return rows_of(_reduced(type_name, msg), log_ns, last_frame_stamp)


class StatusRead(NamedTuple):
    """What the index keeps of one status message (:func:`read`): small, so the export's workers send it back in
    place of the message, and decode it there while scanning instead of in the export's process after the scans."""
    stamp_ns: int | None                # a DiagnosticArray's header stamp; None for a Bool (stamped by its frame)
    ffc: tuple                          # its ffc_status values, in order (a Bool: 2 if true else 0)
    clock_steps: tuple                  # its (header stamp ns, clock_step_ns) pairs (clock_step_values)


def read(type_name: str, data) -> StatusRead:
    """One CDR-serialised status message of type ``type_name`` (:func:`check_type`'s) as the index keeps it;
    ValueError when it is cut short. ``rows_of(read(t, data), ...)`` is ``rows(t, decode(t, data), ...)``."""
    return _reduced(type_name, decode(type_name, data))


def _reduced(type_name: str, msg) -> StatusRead:
    """A decoded status message of type ``type_name`` as :func:`read` gives it: the ``ffc_status`` values that are
    whole numbers, in order."""
    if type_name == BOOL:
        return StatusRead(None, (2 if bool(msg.data) else 0,), ())
    ffc = []
    for st in msg.status:
        values = {kv.key: kv.value for kv in st.values}
        if "ffc_status" in values:
            try:
                ffc.append(int(values["ffc_status"]))
            except ValueError:
                continue
    return StatusRead(msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec, tuple(ffc),
                      tuple(clock_step_values(msg).items()))


def rows_of(status: StatusRead, log_ns: int, last_frame_stamp: int | None) -> list[tuple[int, int]]:
    """The ``(stamp ns, ffc_status)`` rows of one :class:`StatusRead` (as :func:`rows`)."""
    stamp = status.stamp_ns
    if stamp is None:
        stamp = last_frame_stamp if last_frame_stamp is not None else int(log_ns)
    return [(int(stamp), v) for v in status.ffc]


#: the key of the device's status values (firmware/device/clockstep.py) holding the host clock's steps since
#: usb_cam started, in ns (sync.device_clock_steps)
CLOCK_STEP_KEY = "clock_step_ns"


def clock_step_values(msg) -> dict[int, int]:
    """``{header stamp ns: clock_step_ns}`` of one decoded DiagnosticArray status (empty when no status of it
    holds :data:`CLOCK_STEP_KEY` as a whole number)."""
    stamp = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
    out = {}
    for st in msg.status:
        values = {kv.key: kv.value for kv in st.values}
        if CLOCK_STEP_KEY in values:
            try:
                out[stamp] = int(values[CLOCK_STEP_KEY])
            except ValueError:
                continue
    return out


#: how many triggers a status stream may be offset from its frames and still be realigned by an FFC freeze
MAX_LAG_FRAMES = 3
#: frames in a row whose image repeats: an FFC freeze (noise never repeats exactly)
MIN_FREEZE_FRAMES = 3
#: the realigned status must cover the freeze at least this well (intersection over union of the frames)
MIN_AGREEMENT = 0.8


def freeze_runs(frozen) -> np.ndarray:
    """Per frame (recording order): part of a run of at least MIN_FREEZE_FRAMES frames whose image repeats."""
    f = np.asarray(frozen, bool)
    out = np.zeros(len(f), bool)
    i = 0
    while i < len(f):
        j = i
        while j < len(f) and f[j]:
            j += 1
        if j - i >= MIN_FREEZE_FRAMES:
            out[i:j] = True
        i = max(j, i + 1)
    return out


def trigger_index(stamps, counter, period_ns: float) -> np.ndarray:
    """Each frame's trigger count since the first (recording order): from the Boson frame counter when the frames
    carry it, else from the stamps' intervals."""
    from . import counters
    t = np.asarray(stamps, np.int64)
    if counter is not None:
        return counters.pulse_grid_index(t, counter, period_ns)
    return np.concatenate([[0], np.cumsum(np.maximum(1, np.round(np.diff(t) / period_ns).astype(np.int64)))])


def frame_lag(rows: list[tuple[int, int]], frame_stamps, frozen, index) -> int:
    """How many triggers the FFC-in-progress rows of a status stream stamped by its frames (this project's node, a
    Bool stamped by the frame logged before it, the telemetry rows) must move later to lie on the frozen frames:
    an FFC freezes the image for a known span, and that span is in the frames. ``index``: each frame's trigger
    count (:func:`trigger_index`). 0 when there is no freeze, the rows are not on frame stamps, or no lag fits
    clearly better than none."""
    t = np.asarray(frame_stamps, np.int64)
    runs = freeze_runs(frozen)
    if not rows or not runs.any() or len(t) == 0:
        return 0
    pos = {int(s): i for i, s in enumerate(t)}
    on = [(pos.get(int(s)), v) for s, v in rows]
    if sum(i is None for i, _ in on) > max(2, len(on) // 100):
        return 0                                    # stamped on its own clock: not a frame's status
    idx = np.asarray(index, np.int64)
    recorded = set(idx.tolist())
    frozen_k = set(idx[runs].tolist())
    flagged = {int(idx[i]) for i, v in on if i is not None and v == 2}
    if not flagged:
        return 0

    def agreement(lag: int) -> float:
        s = {k + lag for k in flagged} & recorded   # what the freeze can confirm: recorded frames only
        return len(s & frozen_k) / max(len(s | frozen_k), 1)

    scores = {lag: agreement(lag) for lag in range(-MAX_LAG_FRAMES, MAX_LAG_FRAMES + 1)}
    best = max(scores, key=lambda lag: (scores[lag], -abs(lag)))
    return best if best != 0 and scores[best] > scores[0] and scores[best] >= MIN_AGREEMENT else 0


def shifted(rows: list[tuple[int, int]], frame_stamps, lag: int, index) -> list[tuple[int, int]]:
    """The rows moved ``lag`` triggers later: each takes the stamp of the frame of that trigger, and is dropped
    when that frame was not recorded; rows not on a frame are left as they are."""
    if lag == 0:
        return rows
    t = np.asarray(frame_stamps, np.int64)
    idx = np.asarray(index, np.int64)
    pos = {int(s): i for i, s in enumerate(t)}
    frame_of = {int(k): i for i, k in enumerate(idx)}
    out = []
    for s, v in rows:
        i = pos.get(int(s))
        if i is None:
            out.append((s, v))
        elif int(idx[i]) + lag in frame_of:
            out.append((int(t[frame_of[int(idx[i]) + lag]]), v))
    return out
