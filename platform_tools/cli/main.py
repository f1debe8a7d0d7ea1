"""`platform_tools`: the rig's command-line tools. Each subcommand lives in its own module and
registers itself through ``register(subparsers)``."""
from __future__ import annotations

import argparse
from typing import Sequence

from . import boson_cmd, doctor_cmd, firmware_cmd, record_cmd, rig_cmd, simulate_cmd

#: subcommand modules, in the order --help lists them
COMMANDS = [rig_cmd, boson_cmd, firmware_cmd, doctor_cmd, record_cmd, simulate_cmd]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="platform_tools",
        description="Tools of the handheld RGB-thermal rig: the rig description, the Boson cameras, "
                    "the on-device stack and its recordings.",
        epilog="Exit codes: 0 ok, 1 a check failed, 2 bad input or usage.")
    sub = parser.add_subparsers(title="commands", metavar="COMMAND")
    for module in COMMANDS:
        module.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    from .common import dispatch
    return dispatch(build_parser(), argv)


if __name__ == "__main__":
    raise SystemExit(main())
