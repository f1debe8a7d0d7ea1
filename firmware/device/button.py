"""The record button: debounced edges, then presses classified as short or long.

:class:`Button` is pure logic on (time, raw level) samples, so it is tested with exact timings:
a level change is accepted only once it has been stable for ``bounce_s``; a press is reported as
``LONG`` as soon as it has been held for ``long_press_s`` (the user sees the LED react while still
holding), or as ``SHORT`` when released before that.
"""
from __future__ import annotations

import enum
from dataclasses import dataclass


class Press(enum.Enum):
    SHORT = "short"
    LONG = "long"


@dataclass
class Button:
    bounce_s: float
    long_press_s: float
    active_low: bool = True
    _stable_pressed: bool = False
    _candidate: bool | None = None
    _candidate_since: float = 0.0
    _pressed_at: float | None = None
    _long_sent: bool = False
    bounces: int = 0      # raw changes that did not last (for the log)

    def _is_pressed(self, level: int) -> bool:
        return (level == 0) if self.active_low else (level == 1)

    def sample(self, t: float, level: int) -> list[Press]:
        """Feed one raw sample; returns the presses completed by it (zero or one)."""
        pressed = self._is_pressed(level)
        events: list[Press] = []
        if pressed != self._stable_pressed:
            if self._candidate != pressed:
                self._candidate, self._candidate_since = pressed, t
            elif t - self._candidate_since >= self.bounce_s:
                self._accept(pressed, self._candidate_since, events)
        else:
            if self._candidate is not None:
                self.bounces += 1
            self._candidate = None
        if self._stable_pressed and not self._long_sent and self._pressed_at is not None \
                and t - self._pressed_at >= self.long_press_s:
            self._long_sent = True
            events.append(Press.LONG)
        return events

    def _accept(self, pressed: bool, since: float, events: list[Press]) -> None:
        self._stable_pressed = pressed
        self._candidate = None
        if pressed:
            self._pressed_at, self._long_sent = since, False
        else:
            if not self._long_sent:
                events.append(Press.SHORT)
            self._pressed_at = None
