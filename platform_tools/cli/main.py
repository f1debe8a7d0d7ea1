"""`platform_tools`: the rig's command-line tools. Each subcommand lives in its own module and
registers itself through ``register(subparsers)``."""
from __future__ import annotations

import argparse
from typing import Sequence

from platform_tools.rig.conventions import dispatch, tool_parser
from platform_tools.cli import boson_cmd, export_cmd, firmware_cmd, rig_cmd, simulate_cmd, synccheck_cmd
from firmware.commands import doctor as doctor_cmd, record_service as record_cmd

#: subcommand modules, in the order --help lists them
COMMANDS = [rig_cmd, boson_cmd, firmware_cmd, doctor_cmd, record_cmd, simulate_cmd, synccheck_cmd, export_cmd]


def build_parser() -> argparse.ArgumentParser:
    return tool_parser("platform_tools", "Tools of the handheld RGB-thermal rig: the rig description, the Boson "
                       "cameras, the on-device stack and its recordings.", COMMANDS)


def main(argv: Sequence[str] | None = None) -> int:
    return dispatch(build_parser(), argv)


if __name__ == "__main__":
    raise SystemExit(main())
