"""`rig-device doctor` (`platform_tools doctor` on a workstation): the recorder's pre-flight checks on
demand, as a table or JSON."""
from __future__ import annotations

import argparse
import signal
import threading
from pathlib import Path

import json

from firmware.device import bringup
from firmware.device.preflight import Report, run_preflight
from platform_tools.rig import atomic
from platform_tools.rig.conventions import (CheckFailed, UserError, add_output_options, add_rig_options, print_json,
    rig_from_args)


def add_preflight_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("pre-flight")
    g.add_argument("--output-dir", metavar="DIR", type=Path,
                   help="where recordings go (default: recording.output_dir)")
    g.add_argument("--no-boson", action="store_true",
                   help="skip the checks that talk to the Bosons (reported as skipped)")
    g.add_argument("--dev-dir", metavar="DIR", type=Path, default=Path("/dev"),
                   help="where the udev names of the cameras are (default /dev)")
    g.add_argument("--root", metavar="DIR", type=Path, default=Path("/"),
                   help="where /etc and /sys (the pinmux table, the L4T release) are read from (default /)")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("doctor", help="pre-flight checks: data drive, free space, cameras, trigger, sync mode, "
                                      "GPIO pinmux, host clock",
                       description="Run the checks the recorder runs before every recording: the output folder "
                                   "is on the data drive (not the eMMC), enough free space, both Bosons present "
                                   "and answering with the expected serial numbers, their frame counters "
                                   "advancing at the trigger rate, their sync mode as configured, the button and "
                                   "LED pins muxed as GPIOs, the host clock synchronised (chrony).",
                       epilog="Exit 0 when every check passes (or is skipped), 1 when one fails, 2 on bad input.")
    add_rig_options(p)
    add_output_options(p)
    add_preflight_options(p)
    g = p.add_argument_group("bring-up (the first boot of a rig: docs/on-device.md)")
    g.add_argument("--bring-up", action="store_true",
                   help="also check what this project could only assume (USB serials, telemetry layout, trigger, "
                        "ZED SDK / L4T, GPIO pinmux, recorded rate, host clock) and write a report")
    g.add_argument("--frames", metavar="DIR", type=Path,
                   help="folder with left.raw / right.raw: one Y16 frame of each Boson, telemetry rows included")
    g.add_argument("--report-dir", metavar="DIR", type=Path, default=Path("."),
                   help="where bringup-report.json and bringup-report.md go (default: the current folder)")
    p.add_argument("--every", metavar="S", type=float,
                   help="repeat every S seconds until stopped, printing when the result changes")
    p.set_defaults(handler=cmd_doctor)


def _table(report: Report) -> str:
    rows = [f"{c.status:8s} {c.name:16s} {c.detail}" for c in report.checks]
    return "\n".join([f"{'status':8s} {'check':16s} detail"] + rows)


def _once(args, rig) -> Report:
    report = run_preflight(rig, args.output_dir, boson=not args.no_boson, dev_dir=args.dev_dir, root=args.root)
    if getattr(args, "bring_up", False):
        out = Path(args.output_dir or rig.desc.recording.output_dir)
        report.checks += bringup.run(rig, report.cameras, root=args.root, output_dir=out, frames_dir=args.frames,
                                     boson=not args.no_boson)
        atomic.write_text(args.report_dir / "bringup-report.json",
                          json.dumps(report.to_dict() | {"rig": rig.desc.name, "rig_hash": rig.hash}, indent=2,
                                     default=str) + "\n")
        atomic.write_text(args.report_dir / "bringup-report.md",
                          bringup.report_markdown(rig, report.checks, report.cameras))
    return report


def cmd_doctor(args: argparse.Namespace) -> int:
    rig = rig_from_args(args)
    if args.every and args.bring_up:
        raise UserError("--every and --bring-up: the bring-up report is written once; use one of them")
    if args.every:
        return _watch(args, rig)
    report = _once(args, rig)
    if args.json:
        print_json(report.to_dict())
    else:
        print(_table(report))
    if not report.ok:
        raise CheckFailed(f"{len(report.failed())} check(s) failed: " + ", ".join(c.name for c in report.failed()))
    return 0


def _watch(args, rig) -> int:
    stop = threading.Event()
    for sig in (signal.SIGTERM, signal.SIGINT):
        signal.signal(sig, lambda *_: stop.set())
    last = None
    while not stop.is_set():
        report = _once(args, rig)
        key = [(c.name, c.status) for c in report.checks]
        if key != last:
            print_json(report.to_dict()) if args.json else print(_table(report), flush=True)
            last = key
        stop.wait(args.every)
    return 0
