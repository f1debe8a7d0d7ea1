"""`rig-device`: the commands the Orin runs, from the on-device images (the recorder and health
containers of compose.yaml). It imports only firmware and the ground floor (platform_tools.rig,
platform_tools.boson): the images install nothing else. On a workstation the same commands are
`platform_tools doctor`, `platform_tools record-service` and `platform_tools boson-config`.

    rig-device record-service [--rig FILE] ...   the record button and the recorder
    rig-device doctor [--rig FILE] [--json] ...  the pre-flight checks
    rig-device sros2-keys [--out DIR]            the SROS2 keystore of the rig's enclaves
    rig-device boson-config --slave [--json] ... both Bosons in external-sync slave mode, all or nothing
"""
from __future__ import annotations

import argparse
from typing import Sequence

from firmware.commands import boson_config, doctor, record_service, sros2_keys
from platform_tools.rig.conventions import dispatch, tool_parser

#: subcommand modules, in the order --help lists them
COMMANDS = [record_service, doctor, boson_config, sros2_keys]


def build_parser() -> argparse.ArgumentParser:
    return tool_parser("rig-device", "The on-device commands of the handheld RGB-thermal rig: the record "
                       "button's recorder, the pre-flight checks and the Bosons' set-up.", COMMANDS)


def main(argv: Sequence[str] | None = None) -> int:
    return dispatch(build_parser(), argv)


if __name__ == "__main__":
    raise SystemExit(main())
