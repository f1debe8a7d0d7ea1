"""Host clock steps and the thermal stamps: what lets the offline tools undo a step.

usb_cam stamps a frame with the kernel's monotonic time plus a shift to the host clock computed once,
when it starts (upstream-tartanrgbt.md). When the host clock is stepped later (chrony's makestep, a first
NTP sync after boot), the ZED and IMU stamps follow the step and the thermal ones do not. The FFC status
publisher, started with usb_cam in the same container, samples CLOCK_REALTIME - CLOCK_MONOTONIC when it
starts and at every frame, and puts into each frame's status message (header stamp = the frame's):

    realtime_minus_monotonic_ns   the offset now
    clock_step_ns                 the offset now minus the offset at start: how far the host clock has
                                  been stepped since usb_cam computed its shift

so the frame's stamp on the host clock is ``stamp + clock_step_ns`` (`corrected_stamp_ns`). A slewed
clock (chrony's normal discipline) changes the offset by microseconds; only steps matter.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable

#: a change of the offset larger than this counts as a step (publish even when rate-limited)
STEP_NS = 1_000_000


def realtime_minus_monotonic_ns(clock_ns: Callable[[int], int] = time.clock_gettime_ns) -> int:
    """CLOCK_REALTIME - CLOCK_MONOTONIC, the realtime read between two monotonic reads (their midpoint)."""
    m0 = clock_ns(time.CLOCK_MONOTONIC)
    r = clock_ns(time.CLOCK_REALTIME)
    m1 = clock_ns(time.CLOCK_MONOTONIC)
    return r - (m0 + m1) // 2


def corrected_stamp_ns(stamp_ns: int, clock_step_ns: int) -> int:
    """A usb_cam stamp on the host clock as it is now (after the steps `clock_step_ns` sums)."""
    return stamp_ns + clock_step_ns


@dataclass
class ClockSteps:
    """The offset at start and the step since, per sample. `sample` is called per frame."""
    read: Callable[[], int] = realtime_minus_monotonic_ns
    start_ns: int | None = None
    last_step_ns: int = 0

    def __post_init__(self) -> None:
        if self.start_ns is None:
            self.start_ns = self.read()

    def sample(self) -> tuple[dict, bool]:
        """(the values for the status message, whether the step changed by more than STEP_NS)."""
        offset = self.read()
        step = offset - self.start_ns
        jumped = abs(step - self.last_step_ns) > STEP_NS
        self.last_step_ns = step
        return {"realtime_minus_monotonic_ns": offset, "clock_step_ns": step}, jumped
