"""`calibrate`: camera calibration of the rig. Each subcommand lives in its own module and registers
itself through ``register(subparsers)``."""
from __future__ import annotations

import argparse
from typing import Sequence

from platform_tools.rig.conventions import dispatch, tool_parser

from calibration.commands import (detect as detect_cmd, extrinsics as extrinsics_cmd, nominal as nominal_cmd,
    rig as rig_cmd, synth as synth_cmd, thermal as thermal_cmd, thermal_stereo as thermal_stereo_cmd,
    undistort as undistort_cmd, validate as validate_cmd)

COMMANDS = [nominal_cmd, synth_cmd, detect_cmd, thermal_cmd, validate_cmd, extrinsics_cmd, rig_cmd, undistort_cmd,
            thermal_stereo_cmd]


def build_parser() -> argparse.ArgumentParser:
    return tool_parser("calibrate", "Calibrate the rig's cameras: nominal models from the rig description, "
                       "thermal intrinsics from heated-checkerboard images, extrinsics.", COMMANDS)


def main(argv: Sequence[str] | None = None) -> int:
    return dispatch(build_parser(), argv)


if __name__ == "__main__":
    raise SystemExit(main())
