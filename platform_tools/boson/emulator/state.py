"""The emulated Boson's state and how it answers each command (no I/O here).

Settings live in RAM and in a flash image; a reboot reloads RAM from flash, so what was written with
WriteDynamicHeaderToFlash survives and nothing else does. The ISP frame counter runs free at
``free_run_hz`` when external sync is DISABLE or MASTER, and in SLAVE mode advances only with the
pulses of the trigger it is wired to.
"""
from __future__ import annotations

import struct
import threading
import time
from dataclasses import dataclass, field
from typing import Callable

from .. import commands as C
from .. import fslp
from .trigger import Trigger

#: factory settings (FFC AUTO, external sync off, continuous display, 16-bit video, telemetry off)
FACTORY: dict[str, int] = {
    "ext_sync_mode": int(C.ExtSyncMode.DISABLE),
    "ffc_mode": int(C.FfcMode.AUTO),
    "gain_mode": int(C.GainMode.HIGH),
    "telemetry_state": int(C.TelemetryState.DISABLED),
    "telemetry_location": int(C.TelemetryLocation.TOP),
    "telemetry_packing": int(C.TelemetryPacking.DEFAULT),
    "ir16_mode": int(C.Ir16Mode.BITS16),
    "dvo_output_format": int(C.DvoOutputFormat.DEFAULT),
    "display_mode": int(C.DisplayMode.CONTINUOUS),
    "color_lut": 0,
    "agc_mode": 0,
}

# command -> (setting, values allowed) for plain setters, and command -> setting for plain getters
_SETTERS = {
    "bosonSetExtSyncMode": ("ext_sync_mode", range(0, 3)),
    "bosonSetFFCMode": ("ffc_mode", range(0, 4)),
    "bosonSetGainMode": ("gain_mode", range(0, 5)),
    "telemetrySetState": ("telemetry_state", range(0, 2)),
    "telemetrySetLocation": ("telemetry_location", range(0, 2)),
    "telemetrySetPacking": ("telemetry_packing", range(0, 3)),
    "sysctrlSetUsbVideoIR16Mode": ("ir16_mode", range(0, 3)),
    "dvoSetOutputFormat": ("dvo_output_format", range(0, 4)),
    "dvoSetDisplayMode": ("display_mode", range(0, 2)),
    "colorLutSetId": ("color_lut", range(0, 10)),
    "agcSetMode": ("agc_mode", range(0, 16)),
}
_GETTERS = {
    "bosonGetExtSyncMode": "ext_sync_mode",
    "bosonGetFFCMode": "ffc_mode",
    "bosonGetGainMode": "gain_mode",
    "telemetryGetState": "telemetry_state",
    "telemetryGetLocation": "telemetry_location",
    "telemetryGetPacking": "telemetry_packing",
    "dvoGetOutputFormat": "dvo_output_format",
    "colorLutGetId": "color_lut",
    "sysctrlGetUsbVideoIR16Mode": "ir16_mode",
    "dvoGetDisplayMode": "display_mode",
    "agcGetMode": "agc_mode",
}

BAD_COMMAND_ID, INSUFFICIENT, EXCESS, RANGE_ERROR = 0x161, 0x17D, 0x17E, 0x203


@dataclass
class Outcome:
    status: int
    payload: bytes = b""
    reboot: bool = False      # the device reboots after sending this reply


@dataclass
class BosonState:
    serial: int
    sensor_serial: int = 0
    part_number: str = "20640000EMULATED"
    software_rev: tuple[int, int, int] = (4, 1, 0)
    fpa_temp_c_x10: int = 312
    free_run_hz: float = 60.0
    ffc_duration_s: float = 0.5
    trigger: Trigger | None = None
    flash_write_status: int = 0          # set non-zero to emulate a flash write that reports an error
    clock: object = time.monotonic
    settings: dict[str, int] = field(default_factory=lambda: dict(FACTORY))
    flash: dict[str, int] = field(default_factory=lambda: dict(FACTORY))
    flash_writes: int = 0
    boots: int = 1

    def __post_init__(self) -> None:
        self.sensor_serial = self.sensor_serial or self.serial + 100000
        self._lock = threading.RLock()
        self._ffc_started: float | None = None
        self._frames_base = 0.0
        self._epoch_t = self.clock()
        self._epoch_pulses = self._pulses()

    # ------------------------------------------------------------------ frame counter
    def _pulses(self) -> float:
        return self.trigger.pulses() if self.trigger is not None else 0.0

    def _frames_since_epoch(self) -> float:
        if self.settings["ext_sync_mode"] == C.ExtSyncMode.SLAVE:
            return self._pulses() - self._epoch_pulses
        return (self.clock() - self._epoch_t) * self.free_run_hz

    def _new_epoch(self) -> None:
        self._frames_base += self._frames_since_epoch()
        self._epoch_t = self.clock()
        self._epoch_pulses = self._pulses()

    def frame_count(self) -> int:
        with self._lock:
            return int(self._frames_base + self._frames_since_epoch()) & 0xFFFFFFFF

    # ------------------------------------------------------------------ FFC
    def ffc_status(self) -> C.FfcStatus:
        if self._ffc_started is None:
            return C.FfcStatus.NONE
        if self.clock() - self._ffc_started < self.ffc_duration_s:
            return C.FfcStatus.IN_PROGRESS
        return C.FfcStatus.COMPLETE

    # ------------------------------------------------------------------ power cycle
    def reboot(self) -> None:
        with self._lock:
            self.settings = dict(self.flash)
            self.boots += 1
            self._ffc_started = None
            self._frames_base = 0.0
            self._epoch_t = self.clock()
            self._epoch_pulses = self._pulses()

    # ------------------------------------------------------------------ one command
    def handle(self, function_id: int, payload: bytes) -> Outcome:
        cmd = C.BY_ID.get(function_id)
        if cmd is None:
            return Outcome(BAD_COMMAND_ID)
        try:
            args = cmd.decode_request(payload)
        except ValueError as exc:
            return Outcome(INSUFFICIENT if "insufficient" in str(exc) else EXCESS)
        with self._lock:
            return self._dispatch(cmd, args)

    def _dispatch(self, cmd: C.Command, args: tuple) -> Outcome:
        name = cmd.name
        if name in _SETTERS:
            key, allowed = _SETTERS[name]
            if args[0] not in allowed:
                return Outcome(RANGE_ERROR)
            if key == "ext_sync_mode":
                self._new_epoch()
            self.settings[key] = args[0]
            return Outcome(0)
        if name in _GETTERS:
            return Outcome(0, cmd.encode_reply(self.settings[_GETTERS[name]]))
        value = {
            "bosonGetCameraSN": lambda: self.serial,
            "bosonGetSensorSN": lambda: self.sensor_serial,
            "bosonGetCameraPN": lambda: self.part_number,
            "bosonGetSoftwareRev": lambda: self.software_rev,
            "bosonGetFpaTempCelsiusx10": lambda: self.fpa_temp_c_x10,
            "bosonGetFpaTempKelvinx10": lambda: self.fpa_temp_c_x10 + 2732,
            "bosonGetISPFrameCount": self.frame_count,
            "bosonGetFfcStatus": self.ffc_status,
            "bosonGetFFCInProgress": lambda: int(self.ffc_status() == C.FfcStatus.IN_PROGRESS),
            "bosonGetFFCDesired": lambda: 0,
        }.get(name)
        if value is not None:
            return Outcome(0, cmd.encode_reply(value()))
        if name == "bosonRunFFC":
            self._ffc_started = self.clock()
            return Outcome(0)
        if name == "bosonWriteDynamicHeaderToFlash":
            self.flash = dict(self.settings)
            self.flash_writes += 1
            return Outcome(self.flash_write_status)
        if name == "bosonRestoreFactoryDefaultsFromFlash":
            self._new_epoch()
            self.settings = dict(FACTORY)
            return Outcome(0)
        if name == "bosonReboot":
            return Outcome(0, reboot=True)
        return Outcome(BAD_COMMAND_ID)     # in the table but not emulated


def error_payload(function_id: int) -> bytes:
    """The payload of an error reply: zero bytes of the command's normal reply size. FLIR's SDK for
    Python reads a getter's reply payload before it looks at the status, so a reply without those bytes
    makes it raise "Did not receive expected number of bytes" instead of returning the error code
    (seen against this emulator, issue 17). What a real camera sends with an error is NOT known here:
    the zeros are an assumption that keeps the SDK's error path working."""
    cmd = C.BY_ID.get(function_id)
    return bytes(struct.calcsize(cmd.reply)) if cmd is not None and cmd.reply else b""


def answer_with(state: BosonState) -> Callable[[bytes], list[bytes]]:
    """A loopback responder (platform_tools.boson.loopback): request bytes in, the encoded replies of
    ``state`` out, one chunk per reply (no faults, no reboot: the pty device adds those)."""
    decoder = fslp.StreamDecoder()

    def respond(data: bytes) -> list[bytes]:
        out = []
        for item in decoder.feed(data):
            if isinstance(item, fslp.FslpError) or item.channel != fslp.CHANNEL_COMMAND or not item.is_request:
                continue
            outcome = state.handle(item.function_id, item.payload)
            payload = outcome.payload if outcome.status == 0 else error_payload(item.function_id)
            out.append(fslp.encode(fslp.reply(item, outcome.status, payload)))
        return out

    return respond
