"""`platform_tools boson-emulator`: emulated Bosons on pseudo-terminals (platform_tools.boson.emulator),
served until interrupted, or while one platform_tools command runs against them (--run), whose JSON
output, session log and devices --session-out records."""
from __future__ import annotations

import argparse
import contextlib
import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

from platform_tools.boson import discovery
from platform_tools.boson.emulator import Trigger, parse_faults
from platform_tools.boson.emulator.faults import KINDS
from platform_tools.boson.emulator.fleet import Fleet
from platform_tools.rig import atomic
from platform_tools.rig.conventions import UserError, add_output_options, add_rig_options, print_json, rig_from_args


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("boson-emulator", help="run emulated Bosons on pseudo-terminals (for tests and demos)",
                       description="Serve one emulated Boson per --serial on a pseudo-terminal, publish a "
                                   "by-id link usb-FLIR_Boson_<SN>-if00 for each, and print one line per "
                                   "camera: serial, pty, link. Runs until interrupted (SIGUSR1 starts the "
                                   "simulated trigger, SIGUSR2 stops it), for --duration, or while --run runs.",
                       epilog="Faults: KIND[:p=P][:n=N][:fid=0xID][:times=K], comma-separated; kinds: "
                              + ", ".join(KINDS) + ". Exit codes: 0 served until stopped; with --run, the exit "
                              "code of the command run; 2 bad input (--serial, --faults, --faults-on, "
                              "--boot-seconds, the rig).")
    p.add_argument("--serial", type=int, action="append", metavar="N",
                   help="camera serial number (repeat for several cameras; default: the serials set in "
                        "sensors.thermal.left.serial / .right.serial)")
    p.add_argument("--by-id-dir", metavar="DIR",
                   help=f"where to publish the by-id links (default: ${discovery.BY_ID_ENV} or a new temp folder)")
    p.add_argument("--faults", action="append", default=[], metavar="RULES",
                   help="fault rules of every camera (see below)")
    p.add_argument("--faults-on", action="append", default=[], metavar="SN=RULES",
                   help="fault rules of the camera with this serial only, e.g. 93589=delay:s=1.5 (repeatable)")
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


def _serials(args, rig) -> list[int]:
    """--serial, else the serial numbers the rig description sets."""
    thermal = rig.desc.sensors.thermal
    serials = args.serial or [sn for sn in (thermal.left.serial, thermal.right.serial) if sn is not None]
    if not serials:
        raise UserError("--serial: the rig description sets no Boson serial number (sensors.thermal.left.serial, "
                        ".right.serial): give one or more with --serial N")
    if len(set(serials)) != len(serials) or any(s <= 0 or s > 0xFFFFFFFF for s in serials):
        raise UserError("--serial: give distinct serial numbers between 1 and 4294967295")
    return serials


def _faults_on(texts: list[str], serials: list[int]) -> dict[int, list]:
    """--faults-on SN=RULES, each for one of the emulated serials."""
    out: dict[int, list] = {}
    for text in texts:
        sn, sep, rules = text.partition("=")
        if not sep or not sn.strip().isdigit():
            raise UserError(f"--faults-on {text!r}: expected SN=RULES, e.g. {serials[0]}=delay:s=1.5")
        if int(sn) not in serials:
            raise UserError(f"--faults-on {text!r}: SN {sn} is not emulated (--serial: "
                            + ", ".join(map(str, serials)) + ")")
        try:
            out.setdefault(int(sn), []).extend(parse_faults(rules))
        except ValueError as exc:
            raise UserError(f"--faults-on {text!r}: {exc}") from None
    return out


def cmd_emulator(args) -> int:
    rig = rig_from_args(args)
    try:
        faults = parse_faults(args.faults)
    except ValueError as exc:
        raise UserError(f"--faults: {exc}") from None
    serials = _serials(args, rig)
    faults_for = _faults_on(args.faults_on, serials)
    if args.boot_seconds < 0:
        raise UserError("--boot-seconds must be >= 0")
    if args.session_out and not args.run:
        raise UserError("--session-out records a --run session: add --run COMMAND ...")
    trigger = Trigger(args.trigger_hz or rig.desc.sync.rate_hz, running=args.trigger)
    with contextlib.ExitStack() as stack:
        stage = stack.enter_context(atomic.OutputDir(args.session_out)) if args.session_out else None
        log_path = (stage / "session.log") if stage else args.log
        log = stack.enter_context(open(log_path, "w")) if log_path else None
        fleet = stack.enter_context(Fleet(serials, trigger=trigger, by_id_dir=args.by_id_dir, faults=faults,
                                          seed=args.seed, boot_s=args.boot_seconds,
                                          persist_slave=args.persist_slave, log=log, faults_for=faults_for))
        if args.run:
            return _run_session(args, fleet.by_id_dir, fleet.devices, stage)
        _serve_forever(args, fleet.cameras, trigger, fleet.by_id_dir, fleet.devices)
        return 0


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
