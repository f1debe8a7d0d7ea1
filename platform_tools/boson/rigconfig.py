"""The rig's cameras as the ``boson-*`` commands of either tool (``platform_tools``, ``rig-device``) work on
them: which ports hold the cameras asked for, identified by the serial each answers, and ``boson-config``'s
set-up of all of them as one transaction (open every port, then transaction.configure_rig, then its report).

Nothing here parses options or prints: :func:`configure` returns an :class:`Outcome` (the JSON document,
the error lines, the exit code) and hands warnings to a callback as they arise; a selection that cannot
be satisfied is a ``discovery.SelectionError`` (one line), bad input for the command."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterable

from platform_tools.rig.conventions import EXIT_INTERRUPTED
from . import discovery, identity, syncsetup, transaction
from . import operations as ops
from .client import Timeouts
from .codes import PORT_PROBLEMS, BosonError

Warn = Callable[[str], None]

#: the start of a camera's warning that its RAM and flash differ at the end (printed after the report)
RAM_FLASH_WARNING = "RAM and flash differ"


def select(camera: str, port: str | None, rig, pool: ops.ClientPool,
           dev_dir: Path | None = None) -> tuple[list[discovery.Target], list[str]]:
    """The cameras to work on, and warnings: ``port`` as given, else every Boson found (and the rig's udev
    names under ``dev_dir``, the only names a device container has), identified by the serial number each
    answers over its serial link (identity), through ``pool``'s clients, which stay open for the selected
    cameras only. ``camera`` is left, right, all or a serial number. SelectionError for a camera not found,
    missing or duplicated."""
    found = [] if port else discovery.discover()
    if dev_dir is not None and not port:
        found += discovery.udev_ports(rig, dev_dir, found)[0]
    if port or not any(f.source != "usb" for f in found):
        return discovery.select_targets(camera, rig, found, port), []
    identified = identity.identify(found, pool.open, ops.per_camera)
    targets, warnings = identity.assign(camera, rig, identified, found)
    pool.keep(t.port for t in targets)
    return targets, warnings


def configure_targets(targets: list[discovery.Target], pool: ops.ClientPool, plan: syncsetup.Plan,
                      on_signal: Callable[[str], None] | None = None) -> list[syncsetup.CameraResult]:
    """Every camera's client (open since identity), then the plan as one transaction; a camera that
    cannot be opened leaves the others untouched (``aborted``). ``on_signal(line)``: what happens after a
    Ctrl-C / SIGTERM, said at once (transaction.configure_rig); transaction.Interrupted when one stopped it."""
    results = [syncsetup.CameraResult(t.label, t.port, t.serial) for t in targets]

    def open_one(i: int):
        try:
            return pool.open(targets[i])
        except BosonError as exc:
            results[i].error = str(exc)
            results[i].port_problem = isinstance(exc, PORT_PROBLEMS)
            return None
    clients = ops.per_camera(range(len(targets)), open_one)
    if any(c is None for c in clients):
        bad = ", ".join(t.label for t, c in zip(targets, clients) if c is None)
        for r, c in zip(results, clients):
            if c is not None:
                r.status, r.error = "aborted", f"not configured: {bad} could not be opened (all or nothing)"
        return results
    members = [transaction.Member(c, t.serial, r) for c, t, r in zip(clients, targets, results)]
    return transaction.configure_rig(members, plan, on_signal)


@dataclass
class Outcome:
    """What a ``boson-config`` run ended with."""
    doc: dict                                  # syncsetup.summary: what --json prints
    results: list[syncsetup.CameraResult]

    @property
    def late_warnings(self) -> list[str]:
        """The warnings to repeat after the report: a camera whose RAM and flash differ at the end."""
        return [f"{r.label}: {w}" for r in self.results for w in r.warnings if w.startswith(RAM_FLASH_WARNING)]

    @property
    def error_lines(self) -> list[str]:
        """One line per camera that did not end fine."""
        return [r.error_line() for r in self.results if not r.ok]

    @property
    def exit_code(self) -> int:
        """130 when a signal stopped the set-up (every camera put back), 2 when a port could not be opened
        (does not exist, denied, in use), 1 when a camera failed, else 0."""
        if self.doc["interrupted"]:             # the signal that stopped the set-up
            return EXIT_INTERRUPTED
        if any(r.port_problem for r in self.results):
            return 2
        return 0 if self.doc["ok"] else 1


def configure(rig, plan: syncsetup.Plan, *, camera: str = "all", port: str | None = None,
              dev_dir: Path | None = None, timeouts: Timeouts = Timeouts(), retries: int = 3,
              warn: Warn = lambda w: None) -> Outcome:
    """``boson-config`` on the rig: the plan's warnings, then the cameras selected (:func:`select`; its
    warnings), then the plan as one transaction over all of them (all or nothing), each client kept open
    from identity to the end. Warnings go to ``warn`` as they arise, before the work they are about."""
    warnings = syncsetup.plan_warnings(plan, rig)
    _each(warn, warnings)
    interrupted = None
    with ops.ClientPool(timeouts, retries) as pool:
        targets, notes = select(camera, port, rig, pool, dev_dir)
        _each(warn, notes)
        try:
            results = configure_targets(targets, pool, plan, warn)
        except transaction.Interrupted as exc:
            results, interrupted = exc.results, exc.signal_name
    return Outcome(syncsetup.summary(plan, results, warnings) | {"interrupted": interrupted}, results)


def _each(warn: Warn, lines: Iterable[str]) -> None:
    for line in lines:
        warn(line)


def report_lines(doc: dict) -> list[str]:
    """The human-readable report of a ``boson-config`` run (its JSON document): the mode, then each
    camera's status, changes, frame rate, warnings, and what it holds now when it was reverted or failed."""
    out = [f"external sync -> {doc['mode']}" + (" (dry run)" if doc["dry_run"] else "") +
           ((", persisted to flash" if doc["ok"] else ", --persist: not completed (see each camera)")
            if doc["persist"] and not doc["dry_run"] else "")]
    if doc.get("interrupted"):
        out.append(f"stopped by {doc['interrupted']}: every camera was put back")
    for cam in doc["cameras"]:
        sn = f"SN {cam['serial']}" if cam["serial"] is not None else "SN ?"
        who = cam["label"] if cam["label"] == sn else f"{cam['label']:<6} {sn}"
        out.append(f"  {who:<16} {cam['status']:<13} {cam['port']}")
        out += [f"      {ch['setting']}: {ch['from']} -> {ch['to']}" for ch in cam["changes"]]
        if cam["frame_rate_hz"] is not None:
            out.append(f"      frames at {cam['frame_rate_hz']:.1f} Hz")
        out += [f"      warning: {w}" for w in cam["warnings"]]
        if cam["status"] in ("reverted", "failed", "aborted"):
            out.append("      now: " + ", ".join(f"{k} {v}" for k, v in cam["after"].items()))
    return out
