"""The pure part of the health publisher: each camera's frame rate and status, on the topics the released
TartanRGBT stack names (upstream-tartanrgbt.md): ``/health/<camera>/frequency`` and
``/health/<camera>/status`` for ``zed``, ``thermal_left`` and ``thermal_right``.

The node (:mod:`firmware.device.health_node`, on the device only) subscribes to each camera's
camera_info (published once per frame beside the image: 400 bytes instead of an image, the same rate)
and hands the receive times here. Frequency: frames in the last `window_s` over the span they cover.
Status: ``OK`` within RATE_TOLERANCE of sync.rate_hz (the 0.9-1.1 x nominal band others use,
platform.md), ``LOW`` / ``HIGH`` outside it, ``NO DATA`` when no frame arrived for STALE_S.
The message types (std_msgs Float64 and String) are this project's choice: upstream's are not known.
"""
from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

#: health topic names, as the released TartanRGBT stack spells them
FREQUENCY_TOPIC = "/health/{camera}/frequency"
STATUS_TOPIC = "/health/{camera}/status"
#: the band around the trigger rate that counts as healthy (0.9-1.1 x nominal)
RATE_TOLERANCE = 0.1
#: no frame for this long: the camera is reported NO DATA
STALE_S = 1.0
OK, LOW, HIGH, NO_DATA = "OK", "LOW", "HIGH", "NO DATA"


def topics(camera: str) -> dict[str, str]:
    return {"frequency": FREQUENCY_TOPIC.format(camera=camera), "status": STATUS_TOPIC.format(camera=camera)}


@dataclass
class RateMeter:
    """Frames per second over the last `window_s` seconds of receive times."""
    window_s: float
    times: deque = field(default_factory=deque)

    def add(self, t: float) -> None:
        self.times.append(t)
        while self.times and self.times[0] < t - self.window_s:
            self.times.popleft()

    def rate_hz(self, now: float) -> float:
        while self.times and self.times[0] < now - self.window_s:
            self.times.popleft()
        if len(self.times) < 2:
            return 0.0
        return (len(self.times) - 1) / (self.times[-1] - self.times[0])


@dataclass
class CameraHealth:
    camera: str
    expected_hz: float
    window_s: float = 2.0
    meter: RateMeter = None
    last: float | None = None

    def __post_init__(self) -> None:
        self.meter = RateMeter(self.window_s)

    def on_frame(self, t: float) -> None:
        self.meter.add(t)
        self.last = t

    def report(self, now: float) -> tuple[float, str]:
        """(frequency in Hz, status) at time `now` (the same clock as the frame times)."""
        if self.last is None or now - self.last > STALE_S:
            return 0.0, NO_DATA
        hz = self.meter.rate_hz(now)
        if hz < self.expected_hz * (1 - RATE_TOLERANCE):
            return hz, LOW
        if hz > self.expected_hz * (1 + RATE_TOLERANCE):
            return hz, HIGH
        return hz, OK
