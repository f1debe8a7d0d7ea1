"""The command-line options every ``boson-*`` command shares, in whichever tool it is (``platform_tools
boson-*`` on a workstation, ``rig-device boson-config`` on the Orin): which cameras, the serial link's
timeouts and retries, and the exit codes their ``--help`` states. The rig and output options are the
ground floor's (platform_tools.rig.conventions)."""
from __future__ import annotations

import argparse
import shlex
from pathlib import Path

from platform_tools.rig import DEFAULT_RIG
from platform_tools.rig.conventions import UserError

from .client import Timeouts

DEV_DIR = Path("/dev")

#: the exit codes, as every boson-* command's --help states them
EXITS = ("Exit codes: 0 every camera {ok}; 1 a camera failed or did not answer (each camera's row says "
         "how); 2 bad input: an option, the rig description, no camera found, or a port that does not exist, "
         "is denied or is in use.")

#: the boson-config option that asks for each external sync mode (syncsetup.SYNC_MODES), as doctor names it
MODE_FLAGS = {"slave": "--slave", "master": "--master", "disabled": "--no-sync"}


def add_camera_options(p: argparse.ArgumentParser, *, default: str = "all") -> None:
    g = p.add_argument_group("cameras")
    g.add_argument("--camera", default=default, metavar="WHICH",
                   help=f"left, right, all or a serial number (default: {default}); left and right are "
                        "sensors.thermal.left.serial / .right.serial of the rig description")
    g.add_argument("--port", metavar="P", help="use this serial port instead of discovering cameras")
    g.add_argument("--dev-dir", metavar="DIR", type=Path, default=DEV_DIR,
                   help="where the rig's udev names of the camera ports are (<device_name>_serial, as the "
                        "device's containers see them; asked with the ports discovery finds; default /dev)")
    g.add_argument("--timeout", type=float, default=1.0, metavar="S",
                   help="seconds to wait for a reply's first byte (slow commands get 5x; default 1). A "
                        "camera slower than this costs one timeout: its late reply is taken and every later "
                        "command waits twice the latency learned from it")
    g.add_argument("--retries", type=int, default=3, metavar="N", help="retries per command (default 3)")
    g.add_argument("--reopen-timeout", type=float, default=15.0, metavar="S",
                   help="seconds to wait for a camera to come back after it re-enumerates (default 15)")


def timeouts(args: argparse.Namespace) -> Timeouts:
    """The client's timeouts from the camera options (UserError for a value that cannot be)."""
    if args.timeout <= 0 or args.reopen_timeout <= 0 or args.retries < 0:
        raise UserError("--timeout and --reopen-timeout must be positive and --retries >= 0")
    return Timeouts(first_s=args.timeout, rest_s=2 * args.timeout, slow_s=5 * args.timeout,
                    reopen_s=args.reopen_timeout)


def config_command(tool: str, rig, dev_dir: Path = DEV_DIR) -> str:
    """The ``boson-config`` command line that sets the cameras as ``rig`` wants them (its sync mode; the
    telemetry rows come with it), on the same rig file, overrides and udev folder, e.g.
    ``rig-device boson-config --slave --rig /config/rig.yaml``."""
    argv = [tool, "boson-config", MODE_FLAGS[rig.desc.sync.boson_mode]]
    if Path(rig.path).resolve() != DEFAULT_RIG.resolve():
        argv += ["--rig", str(rig.path)]
    for override in rig.overrides:
        argv += ["--set", override]
    if Path(dev_dir) != DEV_DIR:
        argv += ["--dev-dir", str(dev_dir)]
    return shlex.join(argv)
