"""Safe set-up of one camera: read, diff, apply only what differs, read back and verify, check the
trigger, persist, and revert to what was read if any step fails.

Nothing here raises for a camera problem: :func:`configure` returns a :class:`CameraResult` whose
``status`` says in which state the camera was left:

- ``unchanged``     it already had the wanted settings (nothing written)
- ``would-change``  dry run: ``changes`` lists what would be written
- ``configured``    changes applied and verified by reading back (and persisted if asked)
- ``reverted``      a step failed; the settings read at the start were put back and verified
- ``error``         it could not be read at all; nothing was written
- ``failed``        a step failed and the revert could not be verified: ``after`` is what was last read
"""
from __future__ import annotations

import logging
from dataclasses import asdict, dataclass, field
from enum import IntEnum
from typing import Any

from . import commands as C
from .client import BosonClient
from .codes import BosonError, CameraError, IdentityMismatch
from .operations import measure_frame_rate
from .telemetry import EXPECTED_LOCATION

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Setting:
    key: str
    get: C.Command
    set: C.Command
    #: commands sent just before this setting is written, for companions that have no getter in the
    #: protocol reference (so they cannot be diffed or read back): sent only when this setting changes
    before_set: tuple[tuple[C.Command, IntEnum], ...] = ()


SETTINGS: dict[str, Setting] = {
    "ext_sync_mode": Setting("ext_sync_mode", C.GET_EXT_SYNC, C.SET_EXT_SYNC),
    "display_mode": Setting("display_mode", C.GET_DISPLAY_MODE, C.SET_DISPLAY_MODE),
    # telemetry rows carry the FFC status the recorder needs (platform_tools.boson.telemetry); they go
    # where the decoder expects them before they are switched on
    "telemetry_state": Setting("telemetry_state", C.GET_TELEMETRY, C.SET_TELEMETRY, before_set=(
        (C.SET_TELEMETRY_LOCATION, C.TelemetryLocation[EXPECTED_LOCATION.upper()]),)),
}

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
    frame_rate_hz: float | None = None
    warnings: list[str] = field(default_factory=list)
    error: str | None = None
    steps: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return self.status in ("unchanged", "would-change", "configured")

    def to_dict(self) -> dict:
        d = asdict(self)
        for k in ("before", "after"):
            d[k] = {key: C.enum_name(v) for key, v in getattr(self, k).items()}
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
             dry_run: bool = False, check_trigger_s: float | None = None, reboot_verify: bool = False) -> Plan:
    """The plan for the rig (a platform_tools.rig.Rig): external sync ``mode`` ("slave", "master" or
    "disabled"; default sync.boson_mode), telemetry rows on when the rig records them
    (on_device.thermal_telemetry_rows > 0), ``persist`` to flash (default sync.persist), and with
    ``check_trigger_s`` a check that frames arrive at sync.rate_hz over that many seconds (slave only).
    ``display_mode`` "continuous" or "one-shot" also sets dvoSetDisplayMode. ValueError (one line) for a
    combination that cannot be done."""
    sync = rig.desc.sync
    mode = mode or sync.boson_mode
    desired = {"ext_sync_mode": SYNC_MODES[mode]}
    if display_mode:
        desired["display_mode"] = C.DisplayMode[display_mode.upper().replace("-", "_")]
    if rig.desc.on_device.thermal_telemetry_rows > 0:  # the rig records FFC status from telemetry rows
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
    return Plan(desired, persist=persist, dry_run=dry_run, check_trigger=check, reboot_verify=reboot_verify)


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
            "check_trigger": plan.check_trigger is not None, "ok": all(r.ok for r in results),
            "warnings": warnings, "cameras": [r.to_dict() for r in results]}


# ---------------------------------------------------------------------------- small steps
def read_settings(client: BosonClient, keys) -> dict[str, Any]:
    return {k: client.call(SETTINGS[k].get) for k in keys}


def diff(current: dict[str, Any], desired: dict[str, IntEnum]) -> list[tuple[str, Any, IntEnum]]:
    return [(k, current.get(k), v) for k, v in desired.items() if current.get(k) != v]


def apply(client: BosonClient, changes, result: CameraResult) -> None:
    for key, _, value in changes:
        for command, companion in SETTINGS[key].before_set:
            client.call(command, companion)
            result.steps.append(f"{command.name} {C.enum_name(companion)} (not read back: no getter)")
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


def persist(client: BosonClient, desired: dict[str, Any], result: CameraResult) -> None:
    try:
        client.call(C.WRITE_FLASH)
        result.steps.append("wrote settings to flash")
    except CameraError as exc:
        # one public integration saw this fail while the setting still persisted: soft, verify below
        result.warnings.append(f"flash write reported {exc.result_name} (0x{exc.code:03X}); "
                               "settings read back below; confirm after a power cycle")
        result.steps.append(f"flash write reported {exc.result_name}")
    verify(client, desired, "after the flash write")
    result.persisted = True


def reboot_and_verify(client: BosonClient, desired: dict[str, Any], result: CameraResult) -> None:
    client.reboot()
    result.steps.append("rebooted")
    verify(client, desired, "after a reboot (the flash did not keep the settings)")


# ---------------------------------------------------------------------------- one camera
def configure(client: BosonClient, target_serial: int | None, plan: Plan, result: CameraResult) -> CameraResult:
    """Run the plan on one open camera; fills and returns ``result``."""
    keys = list(plan.desired)
    try:
        sn = client.call(C.GET_CAMERA_SN)
        result.serial = sn
        if target_serial is not None and sn != target_serial:
            raise IdentityMismatch(f"{result.port} answers as SN {sn}, not SN {target_serial} as the rig says")
        before = read_settings(client, keys)
    except BosonError as exc:
        result.status, result.error = "error", str(exc)
        return result
    result.before = before
    changes = diff(before, plan.desired)
    result.changes = [{"setting": k, "from": C.enum_name(a), "to": C.enum_name(b)} for k, a, b in changes]
    if plan.dry_run:
        result.status = "would-change" if changes or plan.persist else "unchanged"
        result.after = dict(before)
        return result
    if not changes and not plan.persist and plan.check_trigger is None:
        result.status, result.after = "unchanged", dict(before)
        return result
    reopens = client.reopens
    flash_written = False
    try:
        apply(client, changes, result)
        try:
            result.after = verify(client, plan.desired, "read-back after applying")
        except StepFailed:
            if client.reopens == reopens:
                raise
            # the camera rebooted while we worked: RAM came back from flash; apply once more
            result.warnings.append("the camera re-enumerated during set-up; settings applied again")
            apply(client, diff(read_settings(client, keys), plan.desired), result)
            result.after = verify(client, plan.desired, "read-back after re-applying")
        if plan.check_trigger is not None:
            check_trigger(client, plan.check_trigger, result)
        if plan.persist:
            flash_written = True
            persist(client, plan.desired, result)
            if plan.reboot_verify:
                reboot_and_verify(client, plan.desired, result)
        result.status = "configured" if changes or plan.persist else "unchanged"
        return result
    except BosonError as exc:
        result.error = str(exc)
        revert(client, before, flash_written, result)
        return result


def revert(client: BosonClient, before: dict[str, Any], flash_written: bool, result: CameraResult) -> None:
    """Put back the settings read at the start (and in flash, if this run wrote it); verify."""
    try:
        now = read_settings(client, before)
        apply(client, diff(now, before), result)
        if flash_written:
            client.call(C.WRITE_FLASH)
            result.steps.append("wrote the previous settings to flash")
            result.persisted = False
        result.after = verify(client, before, "revert")
        result.status = "reverted"
        result.steps.append("reverted")
    except BosonError as exc:
        result.status = "failed"
        result.error = f"{result.error}; and the revert failed too: {exc}"
        try:
            result.after = read_settings(client, before)
        except BosonError:
            result.after = {k: "unknown" for k in before}
