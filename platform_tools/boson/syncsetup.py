"""What the set-up of external sync wants of each camera, and its steps on one camera: the plan from
the rig description, the settings (each with its getter, so everything written is read back), read,
diff, apply, verify, check the trigger, write flash. The transaction over the whole rig (all
cameras configured or all put back) is platform_tools.boson.transaction.

A camera's :class:`CameraResult` ``status`` says in which state the run left it:

- ``unchanged``     it already had the wanted settings (nothing written)
- ``would-change``  dry run: ``changes`` lists what would be written
- ``configured``    changes applied and verified by reading back (and persisted if asked)
- ``aborted``       another camera failed before this one was changed: nothing written
- ``reverted``      a step failed on some camera; this one's settings read at the start were put back
                    (and its flash, if this run wrote it) and verified
- ``error``         it could not be read at all; nothing written
- ``failed``        a step failed and the revert could not be verified: ``after`` is what was last read
"""
from __future__ import annotations

import logging
from dataclasses import asdict, dataclass, field
from enum import IntEnum
from typing import Any

from . import commands as C
from .client import BosonClient
from .codes import BosonError, CameraError
from .operations import measure_frame_rate
from .telemetry import EXPECTED_LOCATION

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Setting:
    key: str
    get: C.Command
    set: C.Command


#: every setting the set-up may write, in the order it writes them (the telemetry rows are placed and
#: packed before they are switched on); each has a getter, so each is diffed and read back
SETTINGS: dict[str, Setting] = {s.key: s for s in (
    Setting("ext_sync_mode", C.GET_EXT_SYNC, C.SET_EXT_SYNC),
    Setting("display_mode", C.GET_DISPLAY_MODE, C.SET_DISPLAY_MODE),
    Setting("telemetry_location", C.GET_TELEMETRY_LOCATION, C.SET_TELEMETRY_LOCATION),
    Setting("telemetry_packing", C.GET_TELEMETRY_PACKING, C.SET_TELEMETRY_PACKING),
    Setting("telemetry_state", C.GET_TELEMETRY, C.SET_TELEMETRY),
)}

SYNC_MODES = {"slave": C.ExtSyncMode.SLAVE, "master": C.ExtSyncMode.MASTER, "disabled": C.ExtSyncMode.DISABLE}


@dataclass(frozen=True)
class TriggerCheck:
    """Frames must arrive at ``rate_hz`` within ``tolerance`` (a fraction) over ``window_s``."""
    rate_hz: float
    window_s: float = 0.5
    tolerance: float = 0.25


@dataclass(frozen=True)
class Plan:
    desired: dict[str, IntEnum]
    persist: bool = False
    dry_run: bool = False
    check_trigger: TriggerCheck | None = None
    reboot_verify: bool = False
    #: learn what flash holds (reboot: RAM reloads from flash, then read) so flash is written only when it
    #: differs, RAM/flash differences are reported, and a revert puts the flash back exactly
    read_flash: bool = False

    @property
    def keys(self) -> list[str]:
        """The settings in the order they are written."""
        return [k for k in SETTINGS if k in self.desired]


class StepFailed(BosonError):
    """A verification step failed (read-back differs, no trigger, flash not kept)."""


@dataclass
class CameraResult:
    label: str
    port: str
    serial: int | None = None
    status: str = "error"
    before: dict[str, Any] = field(default_factory=dict)
    after: dict[str, Any] = field(default_factory=dict)
    changes: list[dict[str, Any]] = field(default_factory=list)
    persisted: bool = False
    flash_written: bool = False    # this run sent a flash write (even one whose reply was lost)
    flash_before: dict[str, Any] | None = None   # what flash held at the start (None: not read)
    flash: dict[str, Any] | None = None          # what flash holds at the end, as far as known
    frame_rate_hz: float | None = None
    warnings: list[str] = field(default_factory=list)
    error: str | None = None
    port_problem: bool = False     # the port could not be opened (missing, denied, in use): bad input
    steps: list[str] = field(default_factory=list)
    #: the serial link over the run: requests sent, timeouts, retries, re-openings (platform_tools.boson.transaction)
    link: dict[str, int] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        return self.status in ("unchanged", "would-change", "configured")

    def to_dict(self) -> dict:
        d = asdict(self)
        for k in ("before", "after", "flash_before", "flash"):
            value = getattr(self, k)
            d[k] = None if value is None else {key: C.enum_name(v) for key, v in value.items()}
        d["ok"] = self.ok
        return d

    def error_line(self) -> str:
        """What went wrong, as one line starting with the camera's label (and its status, unless it
        could not be read at all)."""
        text = self.error or ""
        text = text if text.startswith(self.label) else f"{self.label}: {text}"
        return text if self.status == "error" else f"{self.label}: {self.status}: {text.removeprefix(self.label + ': ')}"


# ---------------------------------------------------------------------------- the plan, from the rig
def plan_for(rig, *, mode: str | None = None, display_mode: str | None = None, persist: bool | None = None,
             dry_run: bool = False, check_trigger_s: float | None = None, reboot_verify: bool = False,
             read_flash: bool | None = None) -> Plan:
    """The plan for the rig (a platform_tools.rig.Rig): external sync ``mode`` ("slave", "master" or
    "disabled"; default sync.boson_mode), telemetry rows on when the rig records them
    (on_device.thermal_telemetry_rows > 0), ``persist`` to flash (default sync.persist), and with
    ``check_trigger_s`` a check that frames arrive at sync.rate_hz over that many seconds (slave only).
    ``display_mode`` "continuous" or "one-shot" also sets dvoSetDisplayMode. ``read_flash`` (default: when
    persisting) reboots each camera first to learn what its flash holds. ValueError (one line) for a
    combination that cannot be done."""
    sync = rig.desc.sync
    mode = mode or sync.boson_mode
    desired = {"ext_sync_mode": SYNC_MODES[mode]}
    if display_mode:
        desired["display_mode"] = C.DisplayMode[display_mode.upper().replace("-", "_")]
    if rig.desc.on_device.thermal_telemetry_rows > 0:  # the rig records FFC status from telemetry rows
        # where and how platform_tools.boson.telemetry reads them, then on
        desired["telemetry_location"] = C.TelemetryLocation[EXPECTED_LOCATION.upper()]
        desired["telemetry_packing"] = C.TelemetryPacking.DEFAULT
        desired["telemetry_state"] = C.TelemetryState.ENABLED
    persist = sync.persist if persist is None else persist
    if check_trigger_s is not None and check_trigger_s <= 0:
        raise ValueError("--check-seconds must be positive")
    if reboot_verify and not persist:
        raise ValueError("--reboot-verify checks what was written to flash: use it with --persist")
    check = None
    if check_trigger_s is not None:
        if mode != "slave":
            raise ValueError("--check-trigger applies to --slave (frames per trigger pulse)")
        check = TriggerCheck(rate_hz=sync.rate_hz, window_s=check_trigger_s)
    if read_flash is None:   # flash matters when it is written, and when slave left in it would mean no video
        read_flash = persist or mode != "slave"
    return Plan(desired, persist=persist, dry_run=dry_run, check_trigger=check, reboot_verify=reboot_verify,
                read_flash=read_flash)


def plan_warnings(plan: Plan, rig) -> list[str]:
    """What the user should know before the plan runs (flash in slave mode, a rising trigger edge)."""
    mode = C.enum_name(plan.desired["ext_sync_mode"])
    warnings = []
    if plan.persist and mode == "slave" and not plan.dry_run:
        warnings.append("writing SLAVE mode to flash: after power-up the cameras show no video until the "
                        "trigger runs (use --no-persist to keep it until the next power cycle)")
    if mode == "slave" and rig.desc.sync.edge != "falling":
        warnings.append(f"sync.edge is {rig.desc.sync.edge}; public notes say the Boson triggers on the falling "
                        "edge: check the wiring")
    return warnings


def summary(plan: Plan, results: list[CameraResult], warnings: list[str]) -> dict:
    """The plan and every camera's result, as `boson-config --json` prints it."""
    return {"mode": C.enum_name(plan.desired["ext_sync_mode"]), "persist": plan.persist, "dry_run": plan.dry_run,
            "read_flash": plan.read_flash,
            "check_trigger": plan.check_trigger is not None, "ok": all(r.ok for r in results),
            "warnings": warnings, "cameras": [r.to_dict() for r in results]}


# ---------------------------------------------------------------------------- small steps
def read_settings(client: BosonClient, keys) -> dict[str, Any]:
    return {k: client.call(SETTINGS[k].get) for k in keys}


def diff(current: dict[str, Any], desired: dict[str, IntEnum]) -> list[tuple[str, Any, IntEnum]]:
    return [(k, current.get(k), v) for k, v in desired.items() if current.get(k) != v]


def apply(client: BosonClient, changes, result: CameraResult) -> None:
    for key, _, value in changes:
        client.call(SETTINGS[key].set, value)
        result.steps.append(f"set {key} {C.enum_name(value)}")


def verify(client: BosonClient, desired: dict[str, Any], what: str) -> dict[str, Any]:
    got = read_settings(client, desired)
    bad = [f"{k} is {C.enum_name(got[k])}, expected {C.enum_name(v)}" for k, v in desired.items() if got[k] != v]
    if bad:
        raise StepFailed(f"{what}: " + "; ".join(bad))
    return got


def check_trigger(client: BosonClient, check: TriggerCheck, result: CameraResult) -> None:
    rate = measure_frame_rate(client, check.window_s)
    result.frame_rate_hz = round(rate, 2)
    result.steps.append(f"frame rate {rate:.1f} Hz")
    lo, hi = check.rate_hz * (1 - check.tolerance), check.rate_hz * (1 + check.tolerance)
    if not lo <= rate <= hi:
        why = "no frames: is the trigger running and wired?" if rate == 0 else "wrong rate"
        raise StepFailed(f"trigger check: frames arrive at {rate:.1f} Hz, expected {check.rate_hz:g} Hz "
                         f"+-{check.tolerance:.0%} ({why})")


def write_flash(client: BosonClient, result: CameraResult) -> None:
    """Save RAM as the power-on defaults. A flash write that reports an error is soft (one public
    integration saw the setting persist anyway): a warning, and the caller verifies by reading back."""
    result.flash_written = True        # before sending: a write whose reply is lost may have happened
    try:
        client.call(C.WRITE_FLASH)
        result.steps.append("wrote settings to flash")
    except CameraError as exc:
        result.warnings.append(f"flash write reported {exc.result_name} (0x{exc.code:03X}); "
                               "settings read back; confirm after a power cycle")
        result.steps.append(f"flash write reported {exc.result_name}")


def read_flash(client: BosonClient, keys, result: CameraResult) -> dict[str, Any]:
    """What flash holds for ``keys``: reboot (RAM reloads from flash) and read. RAM is then the flash's."""
    client.reboot()
    result.steps.append("rebooted to read flash")
    return read_settings(client, keys)


def reboot_and_verify(client: BosonClient, desired: dict[str, Any], result: CameraResult) -> None:
    client.reboot()
    result.steps.append("rebooted")
    verify(client, desired, "after a reboot (the flash did not keep the settings)")
