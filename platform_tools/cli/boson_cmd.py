"""`platform_tools boson-*`: configure and inspect the FLIR Boson cameras over serial.

boson-config (external sync, safely), boson-info, boson-ffc, boson-restore-defaults and boson-raw;
boson-emulator (emulated Bosons on pseudo-terminals) is in boson_emulator_cmd. Each command parses,
calls platform_tools.boson (operations, syncsetup) once per camera, and prints. See docs/boson.md.
"""
from __future__ import annotations

import argparse
import sys

from platform_tools.boson import commands as C
from platform_tools.boson import discovery, identity, syncsetup, transaction
from platform_tools.boson import operations as ops
from platform_tools.boson.client import Timeouts
from platform_tools.boson.codes import PORT_PROBLEMS, BosonError
from platform_tools.cli import boson_emulator_cmd
from platform_tools.rig.conventions import (CheckFailed, UserError, add_output_options, add_rig_options, error,
    print_json, rig_from_args)


# ---------------------------------------------------------------------------- shared options
def _add_camera_options(p: argparse.ArgumentParser, *, default: str = "all") -> None:
    g = p.add_argument_group("cameras")
    g.add_argument("--camera", default=default, metavar="WHICH",
                   help=f"left, right, all or a serial number (default: {default}); left and right are "
                        "sensors.thermal.left.serial / .right.serial of the rig description")
    g.add_argument("--port", metavar="P", help="use this serial port instead of discovering cameras")
    g.add_argument("--timeout", type=float, default=1.0, metavar="S",
                   help="seconds to wait for a reply's first byte (slow commands get 5x; default 1). A "
                        "camera slower than this costs one timeout: its late reply is taken and every later "
                        "command waits twice the latency learned from it")
    g.add_argument("--retries", type=int, default=3, metavar="N", help="retries per command (default 3)")
    g.add_argument("--reopen-timeout", type=float, default=15.0, metavar="S",
                   help="seconds to wait for a camera to come back after it re-enumerates (default 15)")


def _timeouts(args) -> Timeouts:
    if args.timeout <= 0 or args.reopen_timeout <= 0 or args.retries < 0:
        raise UserError("--timeout and --reopen-timeout must be positive and --retries >= 0")
    return Timeouts(first_s=args.timeout, rest_s=2 * args.timeout, slow_s=5 * args.timeout,
                    reopen_s=args.reopen_timeout)


def _pool(args) -> ops.ClientPool:
    """The command's clients, one per port, kept open from identity to the end of the command."""
    return ops.ClientPool(_timeouts(args), args.retries)


def _targets(args, rig, pool: ops.ClientPool) -> list[discovery.Target]:
    """The cameras to work on: ``--port`` as given, else every Boson found, identified by the serial
    number each answers over its serial link (platform_tools.boson.identity), through ``pool``'s clients."""
    found = [] if args.port else discovery.discover()
    try:
        if args.port or not any(f.source != "usb" for f in found):
            return discovery.select_targets(str(args.camera), rig, found, args.port)
        identified = identity.identify(found, pool.open, ops.per_camera)
        targets, warnings = identity.assign(str(args.camera), rig, identified, found)
        pool.keep(t.port for t in targets)
    except discovery.SelectionError as exc:
        raise UserError(str(exc)) from None
    if not args.quiet:
        for w in warnings:
            print(f"platform_tools: warning: {w}", file=sys.stderr)
    return targets


def _on_each(args, rig, work, row=lambda target: {}) -> list[dict]:
    """``work(target, client)`` on every selected camera at once: one row per camera, starting with
    label, port and ``row(target)`` (see ops.on_camera)."""
    with _pool(args) as pool:
        return ops.per_camera(_targets(args, rig, pool), lambda t: ops.on_camera(
            t, pool, lambda client: work(t, client), **row(t)))


def _report_errors(rows: list[dict]) -> int:
    """One error line per failed camera; the exit code (2 when a port could not be opened, 1 when a
    camera failed, else 0)."""
    for r in rows:
        if "error" in r:
            error(ops.error_line(r))
    if any(r.get("port_problem") for r in rows):
        return 2
    return 1 if any("error" in r for r in rows) else 0


#: the exit codes, as every boson-* command's --help states them
EXITS = ("Exit codes: 0 every camera {ok}; 1 a camera failed or did not answer (each camera's row says "
         "how); 2 bad input: an option, the rig description, no camera found, or a port that does not exist, "
         "is denied or is in use.")


# ---------------------------------------------------------------------------- registration
def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("boson-config", help="set the Bosons' external sync safely (read, diff, apply, verify)",
                       description="Put the thermal cameras in external-sync slave (or master / no) mode: read "
                                   "the current settings, show the difference, apply only what differs, read "
                                   "back and verify; revert a camera to what was read if any step fails. "
                                   "Defaults come from the rig description's sync section.",
                       epilog=EXITS.format(ok="ended configured or unchanged (all or nothing: when one "
                                                  "fails, every camera is put back)"))
    mode = p.add_mutually_exclusive_group()
    mode.add_argument("--slave", dest="mode", action="store_const", const="slave",
                      help="external-sync slave: one frame per trigger pulse from the capture card")
    mode.add_argument("--master", dest="mode", action="store_const", const="master")
    mode.add_argument("--no-sync", dest="mode", action="store_const", const="disabled",
                      help="external sync disabled (free running)")
    p.add_argument("--persist", action=argparse.BooleanOptionalAction, default=None,
                   help="also write the settings to flash as power-on defaults (default: sync.persist). "
                        "A Boson saved in slave mode shows no video after power-up until pulses arrive")
    p.add_argument("--dry-run", action="store_true", help="read and show the difference; write nothing")
    p.add_argument("--check-trigger", action="store_true",
                   help="after the switch, confirm frames arrive at sync.rate_hz (ISP frame counter); "
                        "revert the camera if they do not")
    p.add_argument("--check-seconds", type=float, default=0.5, metavar="S",
                   help="how long --check-trigger counts frames (default 0.5)")
    p.add_argument("--reboot-verify", action="store_true",
                   help="with --persist: reboot each camera and verify the settings came back from flash")
    p.add_argument("--read-flash", action=argparse.BooleanOptionalAction, default=None,
                   help="reboot each camera first to learn what its flash holds, so flash is written only "
                        "when it differs and a revert restores it exactly (default: with --persist, or when "
                        "leaving slave mode, where slave left in flash means no video at power-up)")
    p.add_argument("--display-mode", choices=["continuous", "one-shot"],
                   help="also set dvoSetDisplayMode (FLIR's ROS sync service sets one-shot with sync; unverified)")
    _add_camera_options(p)
    add_rig_options(p)
    add_output_options(p)
    p.set_defaults(handler=cmd_config)

    p = sub.add_parser("boson-info", help="serials, firmware, temperature, sync/FFC/gain modes of every Boson",
                       description="Read the identity and state of every connected Boson (or --camera).",
                       epilog=EXITS.format(ok="answered"))
    _add_camera_options(p)
    add_rig_options(p)
    add_output_options(p)
    p.set_defaults(handler=cmd_info)

    p = sub.add_parser("boson-ffc", help="run a flat-field correction, or set FFC to auto or manual",
                       description="run: trigger an FFC and wait for it to complete; auto / manual: set the "
                                   "FFC mode and verify it.", epilog=EXITS.format(ok="did it"))
    p.add_argument("action", choices=["run", "auto", "manual"])
    _add_camera_options(p)
    add_rig_options(p)
    add_output_options(p)
    p.set_defaults(handler=cmd_ffc)

    p = sub.add_parser("boson-restore-defaults", help="restore the Bosons' factory settings",
                       description="Restore the factory settings now (bosonRestoreFactoryDefaultsFromFlash); "
                                   "with --persist also save them as power-on defaults. Without --persist "
                                   "the power-on settings stay what flash held (a warning says so).",
                       epilog=EXITS.format(ok="restored them"))
    p.add_argument("--yes", action="store_true", help="do it (required: this discards the camera's settings)")
    p.add_argument("--persist", action="store_true", help="also write them to flash")
    _add_camera_options(p)
    add_rig_options(p)
    add_output_options(p)
    p.set_defaults(handler=cmd_restore)

    p = sub.add_parser("boson-raw", help="send any command by function id; print the reply payload",
                       description="Send one FSLP command to one camera: function id (hex) and an optional "
                                   "payload in hex (big-endian, as the camera expects).",
                       epilog=EXITS.format(ok="answered with success") + " A camera's error code is exit 1.")
    p.add_argument("function_id", metavar="0xID")
    p.add_argument("payload", nargs="?", default="", metavar="HEX", help="request payload, e.g. 00000002")
    p.add_argument("--yes", action="store_true",
                   help="required for the commands that write or erase flash or reboot the camera "
                        "(bosonWriteDynamicHeaderToFlash, bosonRestoreFactoryDefaultsFromFlash, bosonReboot)")
    _add_camera_options(p, default="all")
    add_rig_options(p)
    add_output_options(p)
    p.set_defaults(handler=cmd_raw)

    boson_emulator_cmd.register(sub)


# ---------------------------------------------------------------------------- boson-config
def _plan(args, rig) -> syncsetup.Plan:
    if args.check_seconds <= 0:
        raise UserError("--check-seconds must be positive")
    try:
        return syncsetup.plan_for(rig, mode=args.mode, display_mode=args.display_mode, persist=args.persist,
                                  dry_run=args.dry_run,
                                  check_trigger_s=args.check_seconds if args.check_trigger else None,
                                  reboot_verify=args.reboot_verify, read_flash=args.read_flash)
    except ValueError as exc:
        raise UserError(str(exc)) from None


def _configure_rig(targets, pool: ops.ClientPool, plan) -> list[syncsetup.CameraResult]:
    """Every camera's client (open since identity), then the plan as one transaction; a camera that
    cannot be opened leaves the others untouched (``aborted``)."""
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
    return transaction.configure_rig(members, plan)


def cmd_config(args) -> int:
    rig = rig_from_args(args)
    plan = _plan(args, rig)
    warnings = syncsetup.plan_warnings(plan, rig)
    if not args.quiet:
        for w in warnings:
            print(f"platform_tools: warning: {w}", file=sys.stderr)
    with _pool(args) as pool:
        results = _configure_rig(_targets(args, rig, pool), pool, plan)
    doc = syncsetup.summary(plan, results, warnings)
    if args.json:
        print_json(doc)
    elif not args.quiet:
        _print_config(doc)
    if not args.quiet:
        for r in results:
            for w in r.warnings:
                if w.startswith("RAM and flash differ"):
                    print(f"platform_tools: warning: {r.label}: {w}", file=sys.stderr)
    for r in results:
        if not r.ok:
            error(r.error_line())
    if any(r.port_problem for r in results):
        return 2
    return 0 if doc["ok"] else 1


def _print_config(doc: dict) -> None:
    head = f"external sync -> {doc['mode']}" + (" (dry run)" if doc["dry_run"] else "") + \
        (", persisted to flash" if doc["persist"] and not doc["dry_run"] else "")
    print(head)
    for cam in doc["cameras"]:
        sn = f"SN {cam['serial']}" if cam["serial"] is not None else "SN ?"
        who = cam["label"] if cam["label"] == sn else f"{cam['label']:<6} {sn}"
        print(f"  {who:<16} {cam['status']:<13} {cam['port']}")
        for ch in cam["changes"]:
            print(f"      {ch['setting']}: {ch['from']} -> {ch['to']}")
        if cam["frame_rate_hz"] is not None:
            print(f"      frames at {cam['frame_rate_hz']:.1f} Hz")
        for w in cam["warnings"]:
            print(f"      warning: {w}")
        if cam["status"] in ("reverted", "failed", "aborted"):
            print(f"      now: " + ", ".join(f"{k} {v}" for k, v in cam["after"].items()))


# ---------------------------------------------------------------------------- boson-info
INFO_COLUMNS = ["label", "serial", "part_number", "firmware", "fpa_temp_c", "sync_mode", "ffc_mode", "ffc_status",
                "gain_mode", "frame_count", "port"]


def cmd_info(args) -> int:
    rows = _on_each(args, rig_from_args(args), lambda t, c: ops.camera_info(c, t.serial),
                    row=lambda t: {"video": t.video})
    if args.json:
        print_json({"cameras": rows})
    elif not args.quiet:
        table = [INFO_COLUMNS] + [[str(r.get(c, "-")) for c in INFO_COLUMNS] for r in rows if "serial" in r]
        widths = [max(len(row[i]) for row in table) for i in range(len(INFO_COLUMNS))]
        for row in table if len(table) > 1 else []:     # no header over an empty table
            print("  ".join(v.ljust(w) for v, w in zip(row, widths)).rstrip())
    return _report_errors(rows)


# ---------------------------------------------------------------------------- boson-ffc
def cmd_ffc(args) -> int:
    work = (lambda t, c: ops.run_ffc(c)) if args.action == "run" else (lambda t, c: ops.set_ffc_mode(c, args.action))
    rows = _on_each(args, rig_from_args(args), work, row=lambda t: {"action": args.action})
    if args.json:
        print_json({"cameras": rows})
    elif not args.quiet:
        for r in rows:
            state = r.get("ffc_status", r.get("ffc_mode", "-"))
            print(f"{r['label']:<10} {args.action:<7} {'ok' if 'error' not in r else 'FAILED':<7} {state}")
    return _report_errors(rows)


# ---------------------------------------------------------------------------- boson-restore-defaults
def cmd_restore(args) -> int:
    if not args.yes:
        raise UserError("boson-restore-defaults discards the cameras' current settings: add --yes to do it")
    rows = _on_each(args, rig_from_args(args), lambda t, c: ops.restore_defaults(c, args.persist))
    if not args.persist and not args.quiet:
        print("platform_tools: warning: flash not written: after a power cycle the cameras come back with the "
              "settings saved before (add --persist to save the factory settings)", file=sys.stderr)
    if args.json:
        print_json({"cameras": rows})
    elif not args.quiet:
        for r in rows:
            if "error" not in r:
                print(f"{r['label']:<10} factory settings restored{' and saved to flash' if args.persist else ''}"
                      f" (sync {r['sync_mode']}, FFC {r['ffc_mode']})")
    return _report_errors(rows)


# ---------------------------------------------------------------------------- boson-raw
def _parse_raw(args) -> tuple[int, bytes]:
    try:
        fid = int(args.function_id, 16)
    except ValueError:
        raise UserError(f"function id {args.function_id!r} is not hexadecimal (e.g. 0x00050002)") from None
    if not 0 <= fid <= 0xFFFFFFFF:
        raise UserError(f"function id {args.function_id} does not fit in 32 bits")
    text = args.payload.replace(" ", "").replace(":", "")
    text = text[2:] if text.lower().startswith("0x") else text
    try:
        payload = bytes.fromhex(text)
    except ValueError:
        raise UserError(f"payload {args.payload!r} is not hexadecimal bytes (e.g. 00000002)") from None
    if len(payload) > 1024:
        raise UserError(f"payload of {len(payload)} bytes is too long (at most 1024)")
    return fid, payload


def cmd_raw(args) -> int:
    fid, payload = _parse_raw(args)
    if fid in C.FLASH_OR_REBOOT and not args.yes:
        raise UserError(f"0x{fid:08X} ({C.BY_ID[fid].name}) writes or erases the camera's flash or reboots it: "
                        "add --yes to send it")
    rig = rig_from_args(args)
    with _pool(args) as pool:
        targets = _targets(args, rig, pool)
        if len(targets) != 1:
            raise UserError(f"boson-raw talks to one camera; {len(targets)} match: choose with --camera or --port")
        doc = ops.on_camera(targets[0], pool, lambda c: ops.raw_call(c, fid, payload),
                            **ops.raw_request(fid, payload))
    if args.json:
        print_json(doc)
    elif not args.quiet and "error" not in doc:
        print(doc["reply"] + (f"  ({doc['command']} = {doc['value']})" if "value" in doc else ""))
    if doc.get("port_problem"):
        raise UserError(ops.error_line(doc))
    if "error" in doc:
        raise CheckFailed(ops.error_line(doc))
    return 0
