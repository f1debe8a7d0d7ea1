"""`platform_tools firmware ...`: render the on-device configuration from the rig description, check it."""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

from firmware import pin
from firmware.checks import FAILED, SKIPPED, Check, run_checks
from firmware.render import write
from platform_tools.rig import atomic, load_rig
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

    p = fsub.add_parser("pin", help="the base image digests and download checksums the image builds verify",
                        description="List what the Dockerfiles pull (base images) and download (the ZED SDK "
                                    "installer) with the rig key pinning each. --refresh asks each registry for "
                                    "the image's digest (Docker Registry HTTP API v2) and downloads each archive "
                                    "to hash it, then writes the values into the rig file: only those values "
                                    "change, comments and layout are kept, the file is replaced whole.",
                        epilog="Exit 0 ok; 1 without --refresh when a pin is still unset; 2 on bad input or when "
                               "a host cannot be reached (one line naming it; the rig file is left as it was).")
    add_rig_options(p)
    add_output_options(p)
    p.add_argument("--refresh", action="store_true", help="fetch every pin now and write it into the rig file")
    p.add_argument("--mirror", metavar="HOST=URL", action="append", default=[],
                   help="reach HOST at URL instead (a registry mirror or proxy), e.g. "
                        "registry-1.docker.io=https://mirror.example (repeatable)")
    p.set_defaults(handler=cmd_pin)


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


def _mirrors(specs: list[str]) -> dict[str, str]:
    out = {}
    for spec in specs:
        host, sep, url = spec.partition("=")
        if not sep or not host or not url.startswith(("http://", "https://")):
            raise UserError(f"--mirror {spec}: expected HOST=http(s)://URL")
        out[host] = url
    return out


def cmd_pin(args: argparse.Namespace) -> int:
    rig = rig_from_args(args)
    mirrors = _mirrors(args.mirror)
    pins = pin.pins(rig)
    if not args.refresh:
        if args.json:
            print_json({"rig_file": str(rig.path), "pins": [p.to_dict() for p in pins]})
        else:
            for p in pins:
                print(f"  {'.'.join(p.key):40s} {p.current or 'NOT SET':72s} {p.source}")
        unset = [".".join(p.key) for p in pins if not p.current]
        if unset:
            raise CheckFailed(f"{len(unset)} pin(s) not set: {', '.join(unset)}; run `platform_tools firmware pin "
                              f"--refresh` where there is network")
        return 0
    if args.overrides:
        raise UserError("--set with --refresh: the pins are written into the rig file; edit the file instead")
    try:
        values = {p.key: pin.fetch(p, mirrors) for p in pins}
        text = pin.set_values(rig.path.read_text(), values)
    except pin.PinError as exc:
        raise UserError(f"firmware pin: {exc}; {rig.path} left unchanged") from None
    _write_validated(rig.path, text)
    doc = {"rig_file": str(rig.path), "pins": [{"key": ".".join(p.key), "source": p.source, "old": p.current,
                                                "new": values[p.key]} for p in pins]}
    if args.json:
        print_json(doc)
    elif not args.quiet:
        for row in doc["pins"]:
            print(f"  {row['key']:40s} {row['new']}" + ("" if row["old"] == row["new"] else "   (changed)"))
    return 0


def _write_validated(path: Path, text: str) -> None:
    """Replace the rig file with `text` once it loads as a rig description (the same loader)."""
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".yaml", dir=path.parent)
    try:
        with os.fdopen(fd, "w") as f:
            f.write(text)
        load_rig(tmp)
    finally:
        os.unlink(tmp)
    atomic.write_text(path, text)
