"""`platform_tools boson-*`: configure and inspect the FLIR Boson cameras over serial.

boson-config (external sync, safely), boson-info, boson-ffc, boson-restore-defaults and boson-raw;
boson-emulator (emulated Bosons on pseudo-terminals) is in boson_emulator_cmd. Each command parses,
calls platform_tools.boson (operations, syncsetup) once per camera, and prints. See docs/boson.md.
"""
from __future__ import annotations

import argparse
import sys

from platform_tools.boson import discovery, syncsetup
from platform_tools.boson import operations as ops
from platform_tools.boson.client import Timeouts
from platform_tools.boson.codes import BosonError
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
                   help="seconds to wait for a reply's first byte (slow commands get 5x; default 1)")
    g.add_argument("--retries", type=int, default=3, metavar="N", help="retries per command (default 3)")
    g.add_argument("--reopen-timeout", type=float, default=15.0, metavar="S",
                   help="seconds to wait for a camera to come back after it re-enumerates (default 15)")


def _timeouts(args) -> Timeouts:
    if args.timeout <= 0 or args.reopen_timeout <= 0 or args.retries < 0:
        raise UserError("--timeout and --reopen-timeout must be positive and --retries >= 0")
    return Timeouts(first_s=args.timeout, rest_s=2 * args.timeout, slow_s=5 * args.timeout,
                    reopen_s=args.reopen_timeout)


def _targets(args, rig) -> list[discovery.Target]:
    found = [] if args.port else discovery.discover()
    try:
        return discovery.select_targets(str(args.camera), rig, found, args.port)
    except discovery.SelectionError as exc:
        raise UserError(str(exc)) from None


def _on_each(args, rig, work, row=lambda target: {}) -> list[dict]:
    """``work(target, client)`` on every selected camera at once: one row per camera, starting with
    label, port and ``row(target)`` (see ops.on_camera)."""
    timeouts = _timeouts(args)
    return ops.per_camera(_targets(args, rig), lambda t: ops.on_camera(
        t, timeouts, args.retries, lambda client: work(t, client), **row(t)))


def _report_errors(rows: list[dict]) -> int:
    """One error line per failed camera; the exit code (1 when one failed)."""
    for r in rows:
        if "error" in r:
            error(ops.error_line(r))
    return 1 if any("error" in r for r in rows) else 0


# ---------------------------------------------------------------------------- registration
def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("boson-config", help="set the Bosons' external sync safely (read, diff, apply, verify)",
                       description="Put the thermal cameras in external-sync slave (or master / no) mode: read "
                                   "the current settings, show the difference, apply only what differs, read "
                                   "back and verify; revert a camera to what was read if any step fails. "
                                   "Defaults come from the rig description's sync section.",
                       epilog="Exit 0 when every camera ended configured or unchanged, 1 when one failed "
                              "(each camera's state is reported), 2 for bad input.")
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
    p.add_argument("--display-mode", choices=["continuous", "one-shot"],
                   help="also set dvoSetDisplayMode (FLIR's ROS sync service sets one-shot with sync; unverified)")
    _add_camera_options(p)
    add_rig_options(p)
    add_output_options(p)
    p.set_defaults(handler=cmd_config)

    p = sub.add_parser("boson-info", help="serials, firmware, temperature, sync/FFC/gain modes of every Boson",
                       description="Read the identity and state of every connected Boson (or --camera).")
    _add_camera_options(p)
    add_rig_options(p)
    add_output_options(p)
    p.set_defaults(handler=cmd_info)

    p = sub.add_parser("boson-ffc", help="run a flat-field correction, or set FFC to auto or manual",
                       description="run: trigger an FFC and wait for it to complete; auto / manual: set the "
                                   "FFC mode and verify it.")
    p.add_argument("action", choices=["run", "auto", "manual"])
    _add_camera_options(p)
    add_rig_options(p)
    add_output_options(p)
    p.set_defaults(handler=cmd_ffc)

    p = sub.add_parser("boson-restore-defaults", help="restore the Bosons' factory settings",
                       description="Restore the factory settings now (bosonRestoreFactoryDefaultsFromFlash); "
                                   "with --persist also save them as power-on defaults.")
    p.add_argument("--yes", action="store_true", help="do it (required: this discards the camera's settings)")
    p.add_argument("--persist", action="store_true", help="also write them to flash")
    _add_camera_options(p)
    add_rig_options(p)
    add_output_options(p)
    p.set_defaults(handler=cmd_restore)

    p = sub.add_parser("boson-raw", help="send any command by function id; print the reply payload",
                       description="Send one FSLP command to one camera: function id (hex) and an optional "
                                   "payload in hex (big-endian, as the camera expects).")
    p.add_argument("function_id", metavar="0xID")
    p.add_argument("payload", nargs="?", default="", metavar="HEX", help="request payload, e.g. 00000002")
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
                                  reboot_verify=args.reboot_verify)
    except ValueError as exc:
        raise UserError(str(exc)) from None


def _configure_one(target, args, plan) -> syncsetup.CameraResult:
    result = syncsetup.CameraResult(target.label, target.port, target.serial)
    try:
        client = ops.open_client(target, _timeouts(args), args.retries)
    except BosonError as exc:
        result.error = str(exc)
        return result
    with client:
        return syncsetup.configure(client, target.serial, plan, result)


def cmd_config(args) -> int:
    rig = rig_from_args(args)
    plan = _plan(args, rig)
    warnings = syncsetup.plan_warnings(plan, rig)
    if not args.quiet:
        for w in warnings:
            print(f"platform_tools: warning: {w}", file=sys.stderr)
    results = ops.per_camera(_targets(args, rig), lambda t: _configure_one(t, args, plan))
    doc = syncsetup.summary(plan, results, warnings)
    if args.json:
        print_json(doc)
    elif not args.quiet:
        _print_config(doc)
    for r in results:
        if not r.ok:
            error(r.error_line())
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
        if cam["status"] in ("reverted", "failed"):
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
        for row in table:
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
    targets = _targets(args, rig_from_args(args))
    if len(targets) != 1:
        raise UserError(f"boson-raw talks to one camera; {len(targets)} match: choose with --camera or --port")
    target = targets[0]
    doc = ops.on_camera(target, _timeouts(args), args.retries, lambda c: ops.raw_call(c, fid, payload),
                        **ops.raw_request(fid, payload))
    if args.json:
        print_json(doc)
    elif not args.quiet and "error" not in doc:
        print(doc["reply"] + (f"  ({doc['command']} = {doc['value']})" if "value" in doc else ""))
    if "error" in doc:
        raise CheckFailed(f"{target.label}: {doc['error']}")
    return 0
