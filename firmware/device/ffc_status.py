"""The pure part of the FFC status publisher: from each thermal frame to the status message.

The node (:mod:`firmware.device.ffc_node`, on the device only) hands every received image here;
this module decides what to publish, as the plain dict form of a diagnostic_msgs/DiagnosticArray
(the form :func:`platform_tools.sim.msgs.diagnostic` builds, and what the recorder records on
``on_device.topics.thermal_*_status``). The header stamp is the image's, so each status lines up
with its frame exactly.

Values (strings, as DiagnosticStatus carries them): ``ffc_status`` (0 none, 1 imminent, 2 in
progress, 3 complete: bosonGetFfcStatus's enum), ``ffc_in_progress`` (0/1), ``frame_counter``,
``frames_since_ffc``, ``missed_frames`` (frames the camera counted that never arrived here); with a
clock (`firmware.device.clockstep`), ``realtime_minus_monotonic_ns`` and ``clock_step_ns``: the host
clock steps since start-up, which the offline tools add to the frame's stamp.
Level OK; WARN while an FFC is imminent or in progress (the image is frozen); ERROR when a frame
carries no readable telemetry or its counter does not advance (a stale or repeated frame).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

from firmware.device.clockstep import ClockSteps

from platform_tools.boson.commands import FfcStatus
from platform_tools.boson.telemetry import EXPECTED_LOCATION, Telemetry, TelemetryError, decode_image_data

OK, WARN, ERROR = 0, 1, 2


def diagnostic_dict(stamp_ns: int, name: str, hardware_id: str, values: dict, level: int = OK,
                    message: str = "") -> dict:
    """A diagnostic_msgs/DiagnosticArray as a dict (field names as in the message)."""
    return {"header": {"stamp": {"sec": int(stamp_ns // 1_000_000_000), "nanosec": int(stamp_ns % 1_000_000_000)},
                       "frame_id": ""},
            "status": [{"level": level, "name": name, "message": message, "hardware_id": hardware_id,
                        "values": [{"key": k, "value": str(v)} for k, v in values.items()]}]}


@dataclass
class StatusTracker:
    """Per camera: turns (stamp, image data) into status messages.

    ``period_s`` 0 publishes one status per frame; a positive period publishes on every change of
    the FFC state and otherwise at most once per period."""
    name: str
    hardware_id: str
    rows: int
    location: str = EXPECTED_LOCATION
    period_s: float = 0.0
    clock: Optional[ClockSteps] = None
    _last: Telemetry | None = field(default=None, init=False)
    _last_pub_ns: int | None = field(default=None, init=False)
    _last_state: int | None = field(default=None, init=False)

    def on_frame(self, stamp_ns: int, data: bytes | memoryview, height: int, step: int) -> dict | None:
        try:
            tel = decode_image_data(data, height, step, self.rows, self.location)
        except TelemetryError as exc:
            return self._publish(stamp_ns, -1, {"ffc_status": -1, "ffc_in_progress": 0}, ERROR,
                                 f"no telemetry: {exc}", force=True)
        return self.on_telemetry(stamp_ns, tel)

    def on_telemetry(self, stamp_ns: int, tel: Telemetry) -> dict | None:
        prev, self._last = self._last, tel
        missed = 0
        level, message = OK, ""
        if prev is not None:
            step = (tel.frame_counter - prev.frame_counter) % (1 << 32)
            if step == 0:
                level, message = ERROR, "frame counter did not advance (repeated frame)"
            elif step < 1 << 31:
                missed = step - 1
        if level == OK and tel.ffc_status in (FfcStatus.IMMINENT, FfcStatus.IN_PROGRESS):
            level, message = WARN, f"FFC {tel.ffc_status.name.lower().replace('_', ' ')}"
        values = {"ffc_status": int(tel.ffc_status), "ffc_in_progress": int(tel.ffc_in_progress),
                  "frame_counter": tel.frame_counter, "frames_since_ffc": tel.frames_since_ffc,
                  "missed_frames": missed}
        return self._publish(stamp_ns, int(tel.ffc_status), values, level, message,
                             force=level == ERROR or missed > 0)

    def _publish(self, stamp_ns: int, state: int, values: dict, level: int, message: str,
                 force: bool) -> dict | None:
        if self.clock is not None:
            clock_values, jumped = self.clock.sample()
            values = values | clock_values
            force = force or jumped       # a step is published at the first frame after it
        changed = state != self._last_state
        due = (self.period_s <= 0 or self._last_pub_ns is None
               or stamp_ns - self._last_pub_ns >= self.period_s * 1e9 or stamp_ns < self._last_pub_ns)
        self._last_state = state
        if not (changed or due or force):
            return None
        self._last_pub_ns = stamp_ns
        return diagnostic_dict(stamp_ns, self.name, self.hardware_id, values, level, message)
