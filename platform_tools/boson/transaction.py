"""The set-up of external sync as one transaction over the whole rig: every camera ends configured, or
every camera touched is put back to what was read at the start, in RAM and in flash.

Phases, each on every camera at once; a phase starts only when the previous one succeeded on every
camera:

1. **read**: the camera's serial number (identity), its RAM settings, and with ``plan.read_flash`` its
   flash (a reboot reloads RAM from flash, then read);
2. **apply and verify** what differs in RAM; read back (a camera that re-enumerated meanwhile came
   back with its flash settings: applied again);
3. **trigger check** (``plan.check_trigger``);
4. **persist** (``plan.persist``), only now that every camera verified: the flash write is skipped where
   flash is known to hold the wanted settings already; then ``plan.reboot_verify``.

If any step fails on any camera, every camera whose RAM or flash this run changed is reverted: flash
first (the settings it held at the start, when read, else the RAM read at the start), then RAM, each
verified by reading back. A camera not touched yet is ``aborted``. Every camera's final RAM is read
back into ``after``; ``flash`` is what its flash holds as far as the run knows, and a warning says when
RAM and flash differ (the camera comes back otherwise after a power cycle).

Ctrl-C and SIGTERM (``docker stop``) are held for the whole transaction (platform_tools.rig.interrupts): the
step in progress ends on every camera (a command is never cut in half), then, if a step is left, every
camera is put back as after a failure and :class:`Interrupted` says so; one that comes during the last
step lets it end (one camera's flash new and the other's old is what the transaction exists to prevent),
and a warning says it came too late to stop anything. A second Ctrl-C does not cut the revert short.

Two cameras cannot be written atomically: a power cut during phase 4 can leave one camera's flash new
and the other's old. The next run with ``read_flash`` sees it (the RAM/flash warning) and rewrites only
the camera that needs it; docs/boson.md says so.
"""
from __future__ import annotations

import logging
import signal
from dataclasses import dataclass
from typing import Any, Callable

from platform_tools.rig.interrupts import held
from . import commands as C
from .client import BosonClient
from .codes import BosonError, IdentityMismatch
from .operations import per_camera
from .syncsetup import (CameraResult, Plan, StepFailed, apply, check_trigger, diff, read_flash, read_settings,
                        verify, write_flash)

log = logging.getLogger(__name__)

#: how many times a step is re-done after the camera re-enumerated in the middle of it
REENUMERATION_RETRIES = 2


@dataclass
class Member:
    """One camera in the transaction."""
    client: BosonClient
    target_serial: int | None
    result: CameraResult
    ram: dict[str, Any] | None = None     # what RAM holds now, as far as this run knows
    touched: bool = False                 # this run changed RAM (a revert is owed)
    reopens_seen: int = 0                 # client.reopens when RAM was last verified


# ---------------------------------------------------------------------------- steps on one camera
def _settled(m: Member) -> dict[str, Any] | None:
    """What RAM holds when it is known without asking: read or verified since the last re-enumeration."""
    return m.ram if m.ram is not None and m.client.reopens == m.reopens_seen else None


def _set_ram(m: Member, wanted: dict[str, Any], what: str) -> None:
    """RAM to ``wanted``: write only what differs, read back every setting written; re-applied if the
    camera re-enumerated. No round trip is spent on what an earlier read settles: a setting not written
    is as read just before (nothing re-enumerated since; a setter is assumed to change its own setting
    only, as on the emulator), and a read that finds everything wanted is itself the verification."""
    keys = [k for k in m.result.before if k in wanted] or list(wanted)
    for attempt in range(REENUMERATION_RETRIES + 1):
        if attempt:
            m.result.warnings.append(f"the camera re-enumerated during {what}; settings applied again")
        current = _settled(m)
        if current is None:
            reopens = m.client.reopens
            current = read_settings(m.client, keys)
            if m.client.reopens != reopens:      # a read across a reboot mixes RAM before and after it
                m.ram = None
                continue
            m.ram, m.reopens_seen = current, reopens
        changes = diff(current, wanted)
        if not changes:
            return
        m.touched = True
        reopens = m.client.reopens
        apply(m.client, changes, m.result)
        written = {k: wanted[k] for k, _, _ in changes}
        check = written if m.client.reopens == reopens else dict(wanted)   # a reboot reloaded everything
        try:
            got = verify(m.client, check, what)
        except StepFailed:
            if m.client.reopens == reopens or attempt == REENUMERATION_RETRIES:
                raise
            m.ram = None
            continue
        if m.client.reopens != reopens:          # re-enumerated during the read-back itself
            m.ram = None
            continue
        m.ram, m.reopens_seen = {**current, **got}, reopens
        return
    raise StepFailed(f"{what}: the camera kept re-enumerating")


def _still_set(m: Member, wanted: dict[str, Any], what: str) -> bool:
    """After a step: if the camera re-enumerated since RAM was verified, apply and verify again.
    True when it had re-enumerated."""
    if m.client.reopens == m.reopens_seen:
        return False
    m.result.warnings.append(f"the camera re-enumerated during {what}; settings applied again")
    m.ram = None
    _set_ram(m, wanted, f"re-applying after {what}")
    return True


def _read(m: Member, plan: Plan) -> None:
    sn = m.client.camera_serial()      # asked once per opening: identity may have asked it already
    m.result.serial = sn
    if m.target_serial is not None and sn != m.target_serial:
        raise IdentityMismatch(f"{m.result.port} answers as SN {sn}, not SN {m.target_serial} as the rig says")
    m.result.before = read_settings(m.client, plan.keys)
    m.ram = dict(m.result.before)
    if plan.read_flash and not plan.dry_run:
        m.result.flash_before = read_flash(m.client, plan.keys, m.result)
        m.ram = dict(m.result.flash_before)
        m.touched = m.ram != m.result.before       # RAM now holds the flash's settings
    m.reopens_seen = m.client.reopens
    m.result.changes = [{"setting": k, "from": C.enum_name(a), "to": C.enum_name(b)}
                        for k, a, b in diff(m.result.before, plan.desired)]


def _check_trigger(m: Member, plan: Plan) -> None:
    for attempt in range(REENUMERATION_RETRIES + 1):
        try:
            check_trigger(m.client, plan.check_trigger, m.result)
        except StepFailed:
            # a camera that re-enumerated while counting came back free running (its flash): count again
            if not _still_set(m, plan.desired, "the trigger check") or attempt == REENUMERATION_RETRIES:
                raise
            continue
        if not _still_set(m, plan.desired, "the trigger check"):
            return
    raise StepFailed("trigger check: the camera kept re-enumerating")


def _persist(m: Member, plan: Plan) -> None:
    if m.result.flash_before is not None and not diff(m.result.flash_before, plan.desired):
        m.result.steps.append("flash already holds the wanted settings: not written")
        m.result.flash = dict(m.result.flash_before)
        return
    for _ in range(REENUMERATION_RETRIES + 1):
        write_flash(m.client, m.result)
        # a camera that re-enumerated during the write wrote (if anything) its old RAM: set and write again
        if not _still_set(m, plan.desired, "the flash write"):
            break
    else:
        raise StepFailed("flash write: the camera kept re-enumerating")
    # RAM is as verified (a flash write saves RAM, it does not change it; a re-enumeration during the
    # write was re-applied and verified above): no read-back needed here
    m.result.persisted = True
    m.result.flash = dict(plan.desired)
    if plan.reboot_verify:
        m.client.reboot()
        m.result.steps.append("rebooted")
        m.ram = verify(m.client, plan.desired, "after a reboot (the flash did not keep the settings)")
        m.reopens_seen = m.client.reopens


def _revert(m: Member) -> None:
    """Flash, then RAM, back to what was read at the start; verified. Sets the final status."""
    r = m.result
    if not m.touched and not r.flash_written:
        r.status = "aborted"
        return
    try:
        if r.flash_written:
            old = r.flash_before if r.flash_before is not None else r.before
            if r.flash_before is None:
                r.warnings.append("what flash held before this run was not read (--read-flash): it now holds "
                                  "the settings read from RAM at the start")
            m.ram = None
            _set_ram(m, old, "restoring flash")
            for _ in range(REENUMERATION_RETRIES + 1):
                write_flash(m.client, r)
                if not _still_set(m, old, "the flash restore"):
                    break
            r.steps.append("wrote the previous settings to flash")
            r.persisted, r.flash = False, dict(old)
        m.ram = None
        _set_ram(m, r.before, "revert")
        r.status = "reverted"
        r.steps.append("reverted")
    except BosonError as exc:
        r.status = "failed"
        r.error = f"{r.error}; and the revert failed too: {exc}"


def _final_read(m: Member, plan: Plan) -> None:
    """``after``: the last read-back when nothing happened since (no re-enumeration), else read now."""
    r = m.result
    try:
        fresh = m.ram is not None and m.client.reopens == m.reopens_seen and set(m.ram) == set(plan.keys)
        r.after = dict(m.ram) if fresh else read_settings(m.client, plan.keys)
    except BosonError as exc:
        r.after = {k: "unknown" for k in plan.keys}
        r.warnings.append(f"final read-back failed: {exc}")
        return
    if r.flash is None and r.flash_before is not None and not r.flash_written:
        r.flash = dict(r.flash_before)
    if r.flash is not None:
        differ = [f"{k} {C.enum_name(r.flash[k])} in flash, {C.enum_name(v)} now" for k, v in r.after.items()
                  if k in r.flash and r.flash[k] != v]
        if differ:
            r.warnings.append("RAM and flash differ (after a power cycle the camera comes back with its flash "
                              "settings): " + "; ".join(differ) + "; use --persist to save the current ones")


# ---------------------------------------------------------------------------- the whole rig
def _phase(members: list[Member], step: Callable[[Member], None]) -> list[tuple[Member, BosonError]]:
    """``step`` on every camera at once; the cameras where it raised, with what."""
    def one(m: Member) -> BosonError | None:
        try:
            step(m)
        except BosonError as exc:
            return exc
        return None
    return [(m, e) for m, e in zip(members, per_camera(members, one)) if e is not None]


def _fail(members: list[Member], failed: list[tuple[Member, BosonError]], phase: str, plan: Plan) -> None:
    culprits = {id(m) for m, _ in failed}
    for m, exc in failed:
        m.result.error = str(exc)
    names = ", ".join(m.result.label for m, _ in failed)
    for m in members:
        if id(m) not in culprits:
            m.result.error = f"not configured: {names} failed at the {phase} step (the rig is set up all or nothing)"
    for m, exc in failed:
        if phase == "read" and not m.touched:
            m.result.status = "error"
    _put_back(members, plan)


def _put_back(members: list[Member], plan: Plan) -> None:
    per_camera([m for m in members if m.result.status != "error"], _revert)
    per_camera([m for m in members if m.result.status != "error"], lambda m: _final_read(m, plan))


def _stop(members: list[Member], name: str, phase: str, plan: Plan) -> None:
    """An interrupt after ``phase`` ended on every camera: every camera put back, as after a failure."""
    for m in members:
        m.result.error = f"not configured: {name} came during the {phase} step; every camera was put back"
    _put_back(members, plan)


class Interrupted(Exception):
    """The transaction stopped by ``signal_name`` (SIGINT, SIGTERM) before its last step: every camera was put
    back (``results``, as :func:`configure_rig` returns them)."""

    def __init__(self, signal_name: str, results: list[CameraResult]):
        super().__init__(f"{signal_name}: stopped; every camera was put back")
        self.signal_name = signal_name
        self.results = results


def link_stats(client: BosonClient) -> dict[str, int]:
    """What the run cost on a camera's serial link (this client's life: identity included)."""
    st = client.stats
    return {"requests": client.requests, "timeouts": st.timeouts, "retries": st.retries, "reopens": st.reopens}


class _Signals:
    """SIGINT / SIGTERM during the transaction: the first one's name, and where the transaction was when it came
    (``phase``, ``last``: the last step is under way; ``failing``: a failure is being put back), for the line
    said at once (``on_signal``)."""

    def __init__(self, on_signal: Callable[[str], None] | None):
        self.name: str | None = None
        self.phase, self.last, self.failing = "read", False, False
        self._on_signal = on_signal

    def wake(self, signum: int) -> None:
        """held's wake-up, in the signal handler: the first signal only."""
        if self.name is not None:
            return
        self.name = signal.Signals(signum).name
        if self._on_signal is None:
            return
        if self.failing:
            what = "a camera failed and every camera is being put back: letting that end"
        elif self.last:
            what = f"the last step ({self.phase}) is under way on every camera: letting it end"
        else:
            what = f"stopping after the {self.phase} step, then putting every camera back"
        self._on_signal(f"{self.name}: {what}")


def configure_rig(members: list[Member], plan: Plan,
                  on_signal: Callable[[str], None] | None = None) -> list[CameraResult]:
    """Run ``plan`` on every camera as one transaction (see the module's doc); returns the results in
    the order of ``members``, each with its ``link`` statistics. Never raises for a camera problem: it is
    in the results. SIGINT / SIGTERM are held meanwhile (main thread only: where Python runs handlers);
    ``on_signal(line)`` is told at once, when the first comes, what happens next; :class:`Interrupted` when
    it stopped the transaction."""
    sig = _Signals(on_signal)
    with held(wake=sig.wake) as signals:
        try:
            stopped = _transaction(members, plan, sig)
        finally:
            for m in members:
                m.result.link = link_stats(m.client)
            signals.came.clear()            # acted on here: not raised again as the block ends
    results = [m.result for m in members]
    if stopped:
        raise Interrupted(sig.name, results)
    if sig.name is not None:
        note = ("came during the last step, which ended on every camera: the set-up is complete"
                if all(r.ok for r in results) else "came as the set-up failed; every camera was put back as "
                                                   "after any failure")
        for r in results:
            r.warnings.append(f"{sig.name} {note}")
    return results


def _transaction(members: list[Member], plan: Plan, sig: _Signals) -> bool:
    """The phases (the module's doc); True when a signal stopped them (and every camera was put back)."""
    for m in members:
        m.result.status = "pending"
    sig.last = plan.dry_run                 # a dry run's read is its only step
    failed = _phase(members, lambda m: _read(m, plan))
    if failed:
        sig.failing = True
        _fail(members, failed, "read", plan)
        return False
    if plan.dry_run:
        for m in members:
            m.result.status = "would-change" if m.result.changes or plan.persist else "unchanged"
            m.result.after = dict(m.result.before)
        return False
    steps: list[tuple[str, Callable[[Member], None]]] = [
        ("apply", lambda m: _set_ram(m, plan.desired, "read-back after applying"))]
    if plan.check_trigger is not None:
        steps.append(("trigger check", lambda m: _check_trigger(m, plan)))
    if plan.persist:
        steps.append(("persist", lambda m: _persist(m, plan)))
    for k, (name, step) in enumerate(steps):
        if sig.name is not None:
            _stop(members, sig.name, sig.phase, plan)
            return True
        sig.phase, sig.last = name, k == len(steps) - 1
        failed = _phase(members, step)
        if failed:
            sig.failing = True
            _fail(members, failed, name, plan)
            return False
    for m in members:
        m.result.status = "configured" if m.touched or m.result.persisted else "unchanged"
    per_camera(members, lambda m: _final_read(m, plan))
    return False
