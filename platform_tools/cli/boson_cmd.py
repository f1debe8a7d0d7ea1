"""`platform_tools boson-*`: configure and inspect the FLIR Boson cameras over serial.

boson-info, boson-ffc, boson-restore-defaults and boson-raw; boson-config (external sync, safely) is the
device's command (firmware.commands.boson_config, `rig-device boson-config`), registered here as it is;
boson-emulator (emulated Bosons on pseudo-terminals) is in boson_emulator_cmd. Each command parses,
calls platform_tools.boson (rigconfig, operations) once per camera, and prints. See docs/boson.md.
"""
from __future__ import annotations

import argparse
import sys

from firmware.commands import boson_config
from platform_tools.boson import commands as C
from platform_tools.boson import discovery, options, rigconfig
from platform_tools.boson import operations as ops
from platform_tools.cli import boson_emulator_cmd
from platform_tools.rig.conventions import (CheckFailed, UserError, add_output_options, add_rig_options, error,
    print_json, rig_from_args)


# ---------------------------------------------------------------------------- shared options
def _pool(args) -> ops.ClientPool:
    """The command's clients, one per port, kept open from identity to the end of the command."""
    return ops.ClientPool(options.timeouts(args), args.retries)


def _targets(args, rig, pool: ops.ClientPool) -> list[discovery.Target]:
    """The cameras to work on (rigconfig.select: identified by the serial each answers), through
    ``pool``'s clients; its warnings on stderr."""
    try:
        targets, warnings = rigconfig.select(str(args.camera), args.port, rig, pool, args.dev_dir)
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



# ---------------------------------------------------------------------------- registration
def register(sub: argparse._SubParsersAction) -> None:
    boson_config.register(sub)     # the device's command, the same on a workstation

    p = sub.add_parser("boson-info", help="serials, firmware, temperature, sync/FFC/gain modes of every Boson",
                       description="Read the identity and state of every connected Boson (or --camera).",
                       epilog=options.EXITS.format(ok="answered"))
    options.add_camera_options(p)
    add_rig_options(p)
    add_output_options(p)
    p.set_defaults(handler=cmd_info)

    p = sub.add_parser("boson-ffc", help="run a flat-field correction, or set FFC to auto or manual",
                       description="run: trigger an FFC and wait for it to complete; auto / manual: set the "
                                   "FFC mode and verify it.", epilog=options.EXITS.format(ok="did it"))
    p.add_argument("action", choices=["run", "auto", "manual"])
    options.add_camera_options(p)
    add_rig_options(p)
    add_output_options(p)
    p.set_defaults(handler=cmd_ffc)

    p = sub.add_parser("boson-restore-defaults", help="restore the Bosons' factory settings",
                       description="Restore the factory settings now (bosonRestoreFactoryDefaultsFromFlash); "
                                   "with --persist also save them as power-on defaults. Without --persist "
                                   "the power-on settings stay what flash held (a warning says so).",
                       epilog=options.EXITS.format(ok="restored them"))
    p.add_argument("--yes", action="store_true", help="do it (required: this discards the camera's settings)")
    p.add_argument("--persist", action="store_true", help="also write them to flash")
    options.add_camera_options(p)
    add_rig_options(p)
    add_output_options(p)
    p.set_defaults(handler=cmd_restore)

    p = sub.add_parser("boson-raw", help="send any command by function id; print the reply payload",
                       description="Send one FSLP command to one camera: function id (hex) and an optional "
                                   "payload in hex (big-endian, as the camera expects).",
                       epilog=options.EXITS.format(ok="answered with success") + " A camera's error code is exit 1.")
    p.add_argument("function_id", metavar="0xID")
    p.add_argument("payload", nargs="?", default="", metavar="HEX", help="request payload, e.g. 00000002")
    p.add_argument("--yes", action="store_true",
                   help="required for the commands that write or erase flash or reboot the camera "
                        "(bosonWriteDynamicHeaderToFlash, bosonRestoreFactoryDefaultsFromFlash, bosonReboot)")
    options.add_camera_options(p, default="all")
    add_rig_options(p)
    add_output_options(p)
    p.set_defaults(handler=cmd_raw)

    boson_emulator_cmd.register(sub)


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
