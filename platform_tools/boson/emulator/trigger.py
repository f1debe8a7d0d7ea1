"""The capture card's trigger, simulated: one square wave that drives every emulated Boson wired to
it. Tests start and stop it; the pulse count is computed from the clock, so it costs nothing to run."""
from __future__ import annotations

import threading
import time


class Trigger:
    def __init__(self, rate_hz: float, *, running: bool = False, clock=time.monotonic):
        if rate_hz <= 0:
            raise ValueError("trigger rate must be positive")
        self.rate_hz = float(rate_hz)
        self._clock = clock
        self._lock = threading.Lock()
        self._pulses = 0.0            # pulses before the current run
        self._since: float | None = None
        if running:
            self.start()

    @property
    def running(self) -> bool:
        return self._since is not None

    def start(self) -> None:
        with self._lock:
            if self._since is None:
                self._since = self._clock()

    def stop(self) -> None:
        with self._lock:
            if self._since is not None:
                self._pulses += (self._clock() - self._since) * self.rate_hz
                self._since = None

    def pulses(self) -> float:
        """Pulses since this trigger was made (fractional: the integer part is what was sent)."""
        with self._lock:
            extra = 0.0 if self._since is None else (self._clock() - self._since) * self.rate_hz
            return self._pulses + extra
