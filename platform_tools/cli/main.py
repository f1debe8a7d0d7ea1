"""`platform_tools`: the rig's command-line tools. Each subcommand lives in its own module and
registers itself through ``register(subparsers)``.

Command modules are imported lazily: ``platform_tools COMMAND ...`` imports only the module of COMMAND (importing
every one costs about 1.2 s of CPU: the simulator pulls in scipy, the Boson tools the firmware's), so an export or a
sync-check starts without the others. With no command, ``--help`` or a name no module registers, every module is
imported and the parser is the full one (the same listing and the same error as before)."""
from __future__ import annotations

import argparse
from typing import Sequence

from platform_tools.rig.conventions import dispatch, tool_parser


def _rig():
    from platform_tools.cli import rig_cmd
    return rig_cmd


def _boson():
    from platform_tools.cli import boson_cmd
    return boson_cmd


def _firmware():
    from platform_tools.cli import firmware_cmd
    return firmware_cmd


def _doctor():
    from firmware.commands import doctor
    return doctor


def _record():
    from firmware.commands import record_service
    return record_service


def _simulate():
    from platform_tools.cli import simulate_cmd
    return simulate_cmd


def _sync_check():
    from platform_tools.cli import synccheck_cmd
    return synccheck_cmd


def _export():
    from platform_tools.cli import export_cmd
    return export_cmd


#: (loader of a subcommand module, the commands its ``register`` adds), in the order --help lists them
#: (tests/dataset/test_dataset_speed_cli.py checks the names against what each module registers)
COMMAND_MODULES = [
    (_rig, ("rig",)),
    (_boson, ("boson-config", "boson-info", "boson-ffc", "boson-restore-defaults", "boson-raw", "boson-emulator")),
    (_firmware, ("firmware",)),
    (_doctor, ("doctor",)),
    (_record, ("record-service",)),
    (_simulate, ("simulate-rig",)),
    (_sync_check, ("sync-check",)),
    (_export, ("export",)),
]


def command_modules(argv: Sequence[str] | None = None) -> list:
    """The subcommand modules a parser for ``argv`` needs: the one registering ``argv[0]``, else (no command,
    an option, an unknown name) every one."""
    first = argv[0] if argv else None
    for load, names in COMMAND_MODULES:
        if first in names:
            return [load()]
    return [load() for load, _ in COMMAND_MODULES]


def build_parser(argv: Sequence[str] | None = None) -> argparse.ArgumentParser:
    """The tool's parser; ``argv`` given: with only the command module it names (:func:`command_modules`)."""
    return tool_parser("platform_tools", "Tools of the handheld RGB-thermal rig: the rig description, the Boson "
                       "cameras, the on-device stack and its recordings.", command_modules(argv))


def main(argv: Sequence[str] | None = None) -> int:
    import sys
    argv = list(sys.argv[1:] if argv is None else argv)
    return dispatch(build_parser(argv), argv)


if __name__ == "__main__":
    raise SystemExit(main())
