"""`platform_tools firmware ...`: render the on-device configuration from the rig description, check it."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from firmware.checks import FAILED, SKIPPED, Check, run_checks
from firmware.render import write
from platform_tools.rig.conventions import (CheckFailed, UserError, add_output_options, add_rig_options,
    print_json, rig_from_args)


def register(sub: argparse._SubParsersAction) -> None:
    fw = sub.add_parser("firmware", help="the on-device configuration: docker compose, systemd, udev, ROS 2 launch",
                        description="Render and check the configuration the Orin runs, from the rig description.")
    fsub = fw.add_subparsers(title="firmware commands", metavar="ACTION")

    p = fsub.add_parser("render", help="write compose.yaml, the systemd unit, udev rules, launch and parameter files",
                        description="Render firmware/templates with the rig description into --out (replaced whole), "
                                    "then check the result (compose config, shellcheck, launch files import, unit, "
                                    "udev rules). When a check fails --out is left as it was.")
    add_rig_options(p)
    add_output_options(p)
    p.add_argument("--out", metavar="DIR", required=True, type=Path, help="output folder (replaced whole)")
    p.add_argument("--no-check", action="store_true", help="write without running the checks")
    p.set_defaults(handler=cmd_render)

    p = fsub.add_parser("check", help="check a rendered folder against the rig description",
                        description="Run the checks of `firmware render` on an existing folder.")
    add_rig_options(p)
    add_output_options(p)
    p.add_argument("folder", metavar="DIR", type=Path, help="a folder written by `firmware render`")
    p.set_defaults(handler=cmd_check)


def _print_results(results: list[Check]) -> None:
    for r in results:
        print(f"  {r.status:7s} {r.name:22s} {r.detail}")


def _failed(results: list[Check]) -> list[Check]:
    return [r for r in results if r.status == FAILED]


def cmd_render(args: argparse.Namespace) -> int:
    rig = rig_from_args(args)
    results: list[Check] = []

    def check(stage: Path) -> None:
        results.extend(run_checks(stage, rig))
        bad = _failed(results)
        if bad:
            if not args.json:
                _print_results(results)
            raise CheckFailed(f"firmware render: {bad[0].name} failed ({bad[0].detail}); {args.out} left unchanged")

    try:
        doc = write(rig, args.out, None if args.no_check else check)
    except ValueError as exc:  # a rig value no template can express
        raise UserError(str(exc)) from None
    doc["checks"] = [r.to_dict() for r in results]
    if args.json:
        print_json(doc)
        return 0
    if not args.quiet:
        for path in doc["files"]:
            print(args.out / path)
        _print_results(results)
    for w in doc["warnings"] + [f"check {r.name} skipped: {r.detail}" for r in results if r.status == SKIPPED]:
        print(f"warning: {w}", file=sys.stderr)
    return 0


def cmd_check(args: argparse.Namespace) -> int:
    rig = rig_from_args(args)
    if not (args.folder / "compose.yaml").is_file():
        raise UserError(f"{args.folder}: no compose.yaml; render one with `platform_tools firmware render --out DIR`")
    results = run_checks(args.folder, rig)
    if args.json:
        print_json({"folder": str(args.folder), "checks": [r.to_dict() for r in results]})
    else:
        _print_results(results)
    bad = _failed(results)
    if bad:
        raise CheckFailed(f"{args.folder}: {len(bad)} check(s) failed: {', '.join(r.name for r in bad)}")
    return 0
