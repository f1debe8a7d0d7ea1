"""`rig-device boson-config` (`platform_tools boson-config` on a workstation: the same command): put both
Bosons in the rig's external-sync mode as one transaction (platform_tools.boson.rigconfig), as a table or
JSON. It parses, calls rigconfig.configure once and prints; see docs/boson.md."""
from __future__ import annotations

import argparse
import sys

from platform_tools.boson import options, rigconfig, syncsetup
from platform_tools.boson.discovery import SelectionError
from platform_tools.rig.conventions import UserError, add_output_options, add_rig_options, error, print_json, \
    rig_from_args


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("boson-config", help="set the Bosons' external sync safely (read, diff, apply, verify)",
                       description="Put the thermal cameras in external-sync slave (or master / no) mode: read "
                                   "the current settings, show the difference, apply only what differs, read "
                                   "back and verify; revert a camera to what was read if any step fails. "
                                   "Defaults come from the rig description's sync section.",
                       epilog=options.EXITS.format(ok="ended configured or unchanged (all or nothing: when one "
                                                          "fails, every camera is put back)") +
                       " 130 stopped by Ctrl-C or SIGTERM: the step in progress ends on every camera, then every "
                       "camera is put back (one that comes during the last step lets it end, with a warning).")
    mode = p.add_mutually_exclusive_group()
    helps = {"slave": "external-sync slave: one frame per trigger pulse from the capture card",
             "disabled": "external sync disabled (free running)"}
    for name, flag in options.MODE_FLAGS.items():
        mode.add_argument(flag, dest="mode", action="store_const", const=name, help=helps.get(name))
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
    options.add_camera_options(p)
    add_rig_options(p)
    add_output_options(p)
    # the tool it runs in (platform_tools or rig-device) names its warnings, as conventions.error its errors
    p.set_defaults(handler=cmd_config, tool=p.prog.split()[0])


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


def cmd_config(args: argparse.Namespace) -> int:
    rig = rig_from_args(args)
    plan = _plan(args, rig)

    def warn(line: str) -> None:
        if not args.quiet:
            print(f"{args.tool}: warning: {line}", file=sys.stderr)
    try:
        outcome = rigconfig.configure(rig, plan, camera=str(args.camera), port=args.port, dev_dir=args.dev_dir,
                                      timeouts=options.timeouts(args), retries=args.retries, warn=warn)
    except SelectionError as exc:
        raise UserError(str(exc)) from None
    if args.json:
        print_json(outcome.doc)
    elif not args.quiet:
        print("\n".join(rigconfig.report_lines(outcome.doc)))
    for line in outcome.late_warnings:
        warn(line)
    for line in outcome.error_lines:
        error(line)
    return outcome.exit_code
