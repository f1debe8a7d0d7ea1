"""What the LED shows: one pattern per state, blink codes for errors, and whether the power may be cut.

- IDLE       a short blink every 2 s (alive, ready)                        safe to cut the power
- RECORDING  on                                                            do not cut: the open MCAP has no summary
- STOPPING   fast blink, 5 Hz (finishing: the recorder closing its files,
             the post-stop check and recovery, recording.json, the files
             flushed to the drive; also at start-up while the files of a
             recording interrupted by a power loss are checked)            do not cut the power
- ERROR      the error's code as N blinks, then a pause, repeated          safe to cut the power (nothing is open)
- CHECK_OK   three quick blinks (a long press in IDLE ran the pre-flight and all passed)   safe

So the rule a user learns is: **steady or fast blinking, wait; slow or counted blinks, the power may go.**
"""
from __future__ import annotations

import enum

BLINK_ON_S, BLINK_OFF_S, CODE_PAUSE_S = 0.25, 0.25, 1.5
#: the states in which cutting the power loses data (an open file, a check or a flush under way)
DO_NOT_CUT = ("recording", "stopping")


def power_may_be_cut(state: str) -> bool:
    """What the LED pattern of `state` tells the user about the power switch."""
    if state not in ("idle", "recording", "stopping", "error", "check_ok"):
        raise ValueError(f"no LED pattern for state {state!r}")
    return state not in DO_NOT_CUT


class ErrorCode(enum.IntEnum):
    """Blink counts, documented in docs/on-device.md."""
    PREFLIGHT = 1          # a pre-flight check failed (not on the data drive, a camera missing, no trigger)
    RECORDER_CRASHED = 2   # the recorder process died during a recording
    DISK_FULL = 3          # the disk watchdog stopped the recording
    RECORDER_START = 4     # the recorder could not be started
    FILE_DAMAGED = 5       # an MCAP file could not be recovered
    RECORDER_HUNG = 6      # the recorder ignored SIGINT and had to be killed (its files were recovered)


def level_at(state: str, t: float, code: int = 0) -> int:
    """LED level (0/1) for a state at time t (seconds, any origin)."""
    if state == "recording":
        return 1
    if state == "stopping":
        return 1 if (t % 0.2) < 0.1 else 0
    if state == "idle":
        return 1 if (t % 2.0) < 0.1 else 0
    if state == "check_ok":
        return 1 if (t % 0.3) < 0.15 else 0
    if state == "error":
        period = code * (BLINK_ON_S + BLINK_OFF_S) + CODE_PAUSE_S
        phase = t % period
        if phase >= code * (BLINK_ON_S + BLINK_OFF_S):
            return 0
        return 1 if (phase % (BLINK_ON_S + BLINK_OFF_S)) < BLINK_ON_S else 0
    raise ValueError(f"no LED pattern for state {state!r}")


def count_blinks(levels: list[int]) -> int:
    """Rising edges in a sequence of levels (tests and the log use it to read a blink code)."""
    return sum(1 for a, b in zip(levels, levels[1:]) if a == 0 and b == 1)
