"""`platform_tools boson-*`: configure, inspect and exercise the FLIR Boson cameras over serial.

boson-config (external sync, safely), boson-info, boson-ffc, boson-restore-defaults, boson-raw and
boson-emulator (an emulated Boson on a pseudo-terminal). See docs/boson.md.
"""
from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from platform_tools.rig import atomic
from ..boson import commands as C
from ..boson import discovery, syncsetup
from ..boson.client import BosonClient, Timeouts
from ..boson.codes import BosonError, CameraError
from ..boson.transport import SerialTransport
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


def _client(target: discovery.Target, args) -> BosonClient:
    client = BosonClient(SerialTransport(target.port), timeouts=_timeouts(args), retries=args.retries,
                         label=target.label)
    return client.open()


def _per_camera(targets, work):
    """Run ``work(target)`` on every camera at once; one camera's failure never stops the other."""
    with ThreadPoolExecutor(max_workers=max(1, len(targets))) as pool:
        return list(pool.map(work, targets))


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

    p = sub.add_parser("boson-emulator", help="run emulated Bosons on pseudo-terminals (for tests and demos)",
                       description="Serve one emulated Boson per --serial on a pseudo-terminal, publish a "
                                   "by-id link usb-FLIR_Boson_<SN>-if00 for each, and print one line per "
                                   "camera: serial, pty, link. Runs until interrupted (SIGUSR1 starts the "
                                   "simulated trigger, SIGUSR2 stops it), for --duration, or while --run runs.",
                       epilog="Faults: KIND[:p=P][:n=N][:fid=0xID][:times=K], comma-separated; kinds: drop, "
                              "split, badcrc, wrongseq, garbage, stall, busy, notready, reboot.")
    p.add_argument("--serial", type=int, action="append", metavar="N",
                   help="camera serial number (repeat for several cameras; default 93588)")
    p.add_argument("--by-id-dir", metavar="DIR",
                   help=f"where to publish the by-id links (default: ${discovery.BY_ID_ENV} or a new temp folder)")
    p.add_argument("--faults", action="append", default=[], metavar="RULES", help="fault rules (see below)")
    p.add_argument("--seed", type=int, default=0, help="random seed of the faults")
    p.add_argument("--boot-seconds", type=float, default=0.5, metavar="S", help="simulated boot time (default 0.5)")
    p.add_argument("--trigger", action="store_true", help="start with the simulated trigger running")
    p.add_argument("--trigger-hz", type=float, metavar="HZ", help="trigger rate (default: sync.rate_hz)")
    p.add_argument("--persist-slave", action="store_true",
                   help="start as if slave mode had been saved to flash earlier")
    p.add_argument("--log", metavar="FILE", type=Path, help="write every request and reply as JSON lines")
    p.add_argument("--duration", type=float, metavar="S", help="stop after S seconds")
    p.add_argument("--session-out", metavar="DIR", type=Path,
                   help="with --run: write the command's JSON output, the session log and the devices here")
    p.add_argument("--run", nargs=argparse.REMAINDER, metavar="COMMAND",
                   help="run this platform_tools command against the emulators, then stop (must be last)")
    add_rig_options(p)
    add_output_options(p)
    p.set_defaults(handler=cmd_emulator)


# ---------------------------------------------------------------------------- boson-config
def _plan(args, rig) -> syncsetup.Plan:
    sync = rig.desc.sync
    mode = args.mode or sync.boson_mode
    desired = {"ext_sync_mode": syncsetup.SYNC_MODES[mode]}
    if args.display_mode:
        desired["display_mode"] = C.DisplayMode[args.display_mode.upper().replace("-", "_")]
    if rig.desc.on_device.thermal_telemetry_rows > 0:  # the rig records FFC status from telemetry rows
        desired["telemetry_state"] = C.TelemetryState.ENABLED
    persist = sync.persist if args.persist is None else args.persist
    if args.check_seconds <= 0:
        raise UserError("--check-seconds must be positive")
    if args.reboot_verify and not persist:
        raise UserError("--reboot-verify checks what was written to flash: use it with --persist")
    check = None
    if args.check_trigger:
        rate = sync.rate_hz if mode == "slave" else None
        if rate is None:
            raise UserError("--check-trigger applies to --slave (frames per trigger pulse)")
        check = syncsetup.TriggerCheck(rate_hz=rate, window_s=args.check_seconds)
    return syncsetup.Plan(desired, persist=persist, dry_run=args.dry_run, check_trigger=check,
                          reboot_verify=args.reboot_verify)


def _configure_one(target, args, plan) -> syncsetup.CameraResult:
    result = syncsetup.CameraResult(target.label, target.port, target.serial)
    try:
        client = _client(target, args)
    except BosonError as exc:
        result.error = str(exc)
        return result
    with client:
        return syncsetup.configure(client, target.serial, plan, result)


def cmd_config(args) -> int:
    rig = rig_from_args(args)
    plan = _plan(args, rig)
    mode = C.enum_name(plan.desired["ext_sync_mode"])
    warnings = []
    if plan.persist and mode == "slave" and not args.dry_run:
        warnings.append("writing SLAVE mode to flash: after power-up the cameras show no video until the "
                        "trigger runs (use --no-persist to keep it until the next power cycle)")
    if mode == "slave" and rig.desc.sync.edge != "falling":
        warnings.append(f"sync.edge is {rig.desc.sync.edge}; public notes say the Boson triggers on the falling "
                        "edge: check the wiring")
    if not args.quiet:
        for w in warnings:
            print(f"platform_tools: warning: {w}", file=sys.stderr)
    targets = _targets(args, rig)
    results = _per_camera(targets, lambda t: _configure_one(t, args, plan))
    ok = all(r.ok for r in results)
    doc = {"mode": mode, "persist": plan.persist, "dry_run": plan.dry_run,
           "check_trigger": plan.check_trigger is not None, "ok": ok, "warnings": warnings,
           "cameras": [r.to_dict() for r in results]}
    if args.json:
        print_json(doc)
    elif not args.quiet:
        _print_config(doc)
    for r in results:
        if not r.ok:
            text = r.error or ""
            text = text if text.startswith(r.label) else f"{r.label}: {text}"
            error(text if r.status == "error" else f"{r.label}: {r.status}: {text.removeprefix(r.label + ': ')}")
    return 0 if ok else 1


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
INFO_FIELDS = [
    ("serial", C.GET_CAMERA_SN), ("sensor_serial", C.GET_SENSOR_SN), ("part_number", C.GET_CAMERA_PN),
    ("firmware", C.GET_SOFTWARE_REV), ("fpa_temp_c", C.GET_FPA_TEMP_C), ("sync_mode", C.GET_EXT_SYNC),
    ("ffc_mode", C.GET_FFC_MODE), ("ffc_status", C.GET_FFC_STATUS), ("gain_mode", C.GET_GAIN_MODE),
    ("frame_count", C.GET_FRAME_COUNT),
]


def _info_one(target, args) -> dict:
    row: dict = {"label": target.label, "port": target.port, "video": target.video}
    try:
        with _client(target, args) as client:
            for key, cmd in INFO_FIELDS:
                value = client.call(cmd)
                if key == "firmware":
                    value = ".".join(str(v) for v in value)
                elif key == "fpa_temp_c":
                    value = value / 10.0
                row[key] = C.enum_name(value)
        if target.serial is not None and row["serial"] != target.serial:
            row["error"] = f"answers as SN {row['serial']}, not SN {target.serial}"
    except BosonError as exc:
        row["error"] = str(exc)
    return row


def cmd_info(args) -> int:
    rig = rig_from_args(args)
    rows = _per_camera(_targets(args, rig), lambda t: _info_one(t, args))
    if args.json:
        print_json({"cameras": rows})
    elif not args.quiet:
        cols = ["label", "serial", "part_number", "firmware", "fpa_temp_c", "sync_mode", "ffc_mode",
                "ffc_status", "gain_mode", "frame_count", "port"]
        table = [cols] + [[str(r.get(c, "-")) for c in cols] for r in rows if "serial" in r]
        widths = [max(len(row[i]) for row in table) for i in range(len(cols))]
        for row in table:
            print("  ".join(v.ljust(w) for v, w in zip(row, widths)).rstrip())
    for r in rows:
        if "error" in r:
            error(r["error"] if r["error"].startswith(r["label"]) else f"{r['label']}: {r['error']}")
    return 1 if any("error" in r for r in rows) else 0


# ---------------------------------------------------------------------------- boson-ffc
def _ffc_one(target, args) -> dict:
    row: dict = {"label": target.label, "port": target.port, "action": args.action}
    try:
        with _client(target, args) as client:
            if args.action == "run":
                client.call(C.RUN_FFC)
                deadline = time.monotonic() + 5 * args.timeout + 2.0
                status = client.call(C.GET_FFC_STATUS)
                while status in (C.FfcStatus.IMMINENT, C.FfcStatus.IN_PROGRESS) and time.monotonic() < deadline:
                    time.sleep(0.05)
                    status = client.call(C.GET_FFC_STATUS)
                row["ffc_status"] = C.enum_name(status)
                if status in (C.FfcStatus.IMMINENT, C.FfcStatus.IN_PROGRESS):
                    row["error"] = "FFC did not complete in time"
            else:
                want = C.FfcMode[args.action.upper()]
                row["before"] = C.enum_name(client.call(C.GET_FFC_MODE))
                if row["before"] != args.action:
                    client.call(C.SET_FFC_MODE, want)
                row["ffc_mode"] = C.enum_name(client.call(C.GET_FFC_MODE))
                if row["ffc_mode"] != args.action:
                    row["error"] = f"FFC mode reads back {row['ffc_mode']}"
    except BosonError as exc:
        row["error"] = str(exc)
    return row


def cmd_ffc(args) -> int:
    rows = _per_camera(_targets(args, rig_from_args(args)), lambda t: _ffc_one(t, args))
    if args.json:
        print_json({"cameras": rows})
    elif not args.quiet:
        for r in rows:
            state = r.get("ffc_status", r.get("ffc_mode", "-"))
            print(f"{r['label']:<10} {args.action:<7} {'ok' if 'error' not in r else 'FAILED':<7} {state}")
    for r in rows:
        if "error" in r:
            error(r["error"] if r["error"].startswith(r["label"]) else f"{r['label']}: {r['error']}")
    return 1 if any("error" in r for r in rows) else 0


# ---------------------------------------------------------------------------- boson-restore-defaults
def _restore_one(target, args) -> dict:
    row: dict = {"label": target.label, "port": target.port}
    try:
        with _client(target, args) as client:
            client.call(C.RESTORE_DEFAULTS)
            if args.persist:
                client.call(C.WRITE_FLASH)
            row["sync_mode"] = C.enum_name(client.call(C.GET_EXT_SYNC))
            row["ffc_mode"] = C.enum_name(client.call(C.GET_FFC_MODE))
            row["persisted"] = args.persist
    except BosonError as exc:
        row["error"] = str(exc)
    return row


def cmd_restore(args) -> int:
    if not args.yes:
        raise UserError("boson-restore-defaults discards the cameras' current settings: add --yes to do it")
    rows = _per_camera(_targets(args, rig_from_args(args)), lambda t: _restore_one(t, args))
    if args.json:
        print_json({"cameras": rows})
    elif not args.quiet:
        for r in rows:
            if "error" not in r:
                print(f"{r['label']:<10} factory settings restored{' and saved to flash' if args.persist else ''}"
                      f" (sync {r['sync_mode']}, FFC {r['ffc_mode']})")
    for r in rows:
        if "error" in r:
            error(r["error"] if r["error"].startswith(r["label"]) else f"{r['label']}: {r['error']}")
    return 1 if any("error" in r for r in rows) else 0


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
    cmd = C.BY_ID.get(fid)
    doc: dict = {"label": target.label, "port": target.port, "function_id": f"0x{fid:08X}",
                 "command": cmd.name if cmd else None, "request": payload.hex()}
    try:
        with _client(target, args) as client:
            reply = client.call_raw(fid, payload, command=cmd)
        doc.update(status="0x000", reply=reply.hex())
        if cmd is not None and cmd.reply:
            try:
                doc["value"] = C.enum_name(cmd.decode_reply(reply))
            except BosonError:
                pass
    except CameraError as exc:
        doc.update(status=f"0x{exc.code:03X}", result=exc.result_name, error=str(exc))
    except BosonError as exc:
        doc.update(error=str(exc))
    if args.json:
        print_json(doc)
    elif not args.quiet and "error" not in doc:
        print(doc["reply"] + (f"  ({doc['command']} = {doc['value']})" if "value" in doc else ""))
    if "error" in doc:
        raise CheckFailed(f"{target.label}: {doc['error']}")
    return 0


# ---------------------------------------------------------------------------- boson-emulator
def cmd_emulator(args) -> int:
    from ..boson.emulator import BosonState, EmulatedBoson, Trigger, parse_faults

    rig = rig_from_args(args)
    serials = args.serial or [93588]
    if len(set(serials)) != len(serials) or any(s <= 0 or s > 0xFFFFFFFF for s in serials):
        raise UserError("--serial: give distinct serial numbers between 1 and 4294967295")
    try:
        faults = parse_faults(args.faults)
    except ValueError as exc:
        raise UserError(f"--faults: {exc}") from None
    if args.boot_seconds < 0:
        raise UserError("--boot-seconds must be >= 0")
    if args.session_out and not args.run:
        raise UserError("--session-out records a --run session: add --run COMMAND ...")
    trigger = Trigger(args.trigger_hz or rig.desc.sync.rate_hz, running=args.trigger)

    temp_dir = None
    by_id = args.by_id_dir or os.environ.get(discovery.BY_ID_ENV)
    if not by_id:
        temp_dir = tempfile.mkdtemp(prefix="boson-by-id.")
        by_id = temp_dir

    stage_cm = atomic.OutputDir(args.session_out) if args.session_out else None
    stage = stage_cm.__enter__() if stage_cm else None
    log_path = (stage / "session.log") if stage else args.log
    log_file = open(log_path, "w") if log_path else None
    lock = threading.Lock()
    emus = []
    try:
        for i, sn in enumerate(serials):
            state = BosonState(sn, trigger=trigger)
            if args.persist_slave:
                state.flash["ext_sync_mode"] = state.settings["ext_sync_mode"] = int(C.ExtSyncMode.SLAVE)
            emus.append(EmulatedBoson(state, by_id_dir=by_id, faults=[parse_faults(f.spec())[0] for f in faults],
                                      boot_s=args.boot_seconds, seed=args.seed + i, log=log_file,
                                      log_lock=lock).start())
        devices = [{"serial": e.serial, "path": e.path, "link": str(e.link)} for e in emus]
        if args.run:
            code = _run_session(args, by_id, devices, stage)
        else:
            _serve_forever(args, emus, trigger, by_id, devices)
            code = 0
    except BaseException:
        for e in emus:
            e.stop()
        if log_file:
            log_file.close()
        if stage_cm:
            stage_cm.__exit__(*sys.exc_info())
        raise
    for e in emus:
        e.stop()
    if log_file:
        log_file.close()
    if stage_cm:
        stage_cm.__exit__(None, None, None)
    if temp_dir:
        import shutil
        shutil.rmtree(temp_dir, ignore_errors=True)
    return code


def _serve_forever(args, emus, trigger, by_id, devices) -> None:
    if args.json:
        print_json({"by_id_dir": by_id, "devices": devices})
    else:
        for d in devices:
            print(f"{d['serial']} {d['path']} {d['link']}")
        print(f"# export {discovery.BY_ID_ENV}={by_id}  (so the boson-* commands find these cameras)")
    sys.stdout.flush()
    stop = threading.Event()
    handlers = {signal.SIGTERM: lambda *_: stop.set(), signal.SIGINT: lambda *_: stop.set(),
                signal.SIGUSR1: lambda *_: trigger.start(), signal.SIGUSR2: lambda *_: trigger.stop()}
    old = {s: signal.signal(s, h) for s, h in handlers.items()}
    try:
        stop.wait(args.duration)
    finally:
        for s, h in old.items():
            signal.signal(s, h)


def _run_session(args, by_id, devices, stage) -> int:
    argv = list(args.run)
    if argv and argv[0] == "--":
        argv = argv[1:]
    if not argv:
        raise UserError("--run needs a command, e.g. --run boson-config --slave")
    env = dict(os.environ, **{discovery.BY_ID_ENV: by_id})
    cmd = [sys.executable, "-m", "platform_tools.cli.main", *argv]
    t0 = time.monotonic()
    proc = subprocess.run(cmd, env=env, stdout=subprocess.PIPE, text=True)
    seconds = time.monotonic() - t0
    if stage is None:
        sys.stdout.write(proc.stdout)
        return proc.returncode
    try:
        result = json.loads(proc.stdout)
        (stage / "result.json").write_text(json.dumps(result, indent=2) + "\n")
    except json.JSONDecodeError:
        (stage / "result.txt").write_text(proc.stdout)
    session = {"command": ["platform_tools", *argv], "exit_code": proc.returncode, "seconds": round(seconds, 3),
               "by_id_dir": by_id, "devices": devices}
    (stage / "session.json").write_text(json.dumps(session, indent=2) + "\n")
    if not args.quiet:
        print(f"{args.session_out}: exit {proc.returncode} in {seconds:.2f} s")
    return proc.returncode
