"""`platform_tools simulate-rig`: a recording as the rig would write it, without the rig."""
from __future__ import annotations

import argparse
from pathlib import Path

from ..sim.timeline import SimParams
from platform_tools.rig.conventions import (UserError, add_output_options, add_rig_options, print_json,
    rig_from_args)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("simulate-rig", help="write a simulated MCAP recording with known timing faults",
                       description="Write DIR/bag (rosbag2 folder: MCAP with ROS 2 CDR messages on the rig's "
                                   "topics) and DIR/truth.json: ZED left/right JPEG images and depth, IMU, thermal "
                                   "left/right mono16 from one trigger at sync.rate_hz with jitter and offsets, "
                                   "FFC status and frozen frames, dropped frames, one clock step.")
    add_rig_options(p)
    add_output_options(p)
    p.add_argument("--out", metavar="DIR", required=True, type=Path, help="output folder (replaced whole)")
    p.add_argument("--duration", metavar="S", type=float, default=60.0, help="seconds to simulate (default 60)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--scale", type=float, default=0.25,
                   help="image size as a fraction of the published size (default 0.25; 1 for full size)")
    p.add_argument("--drop-probability", type=float, default=0.005, metavar="P",
                   help="chance each frame is dropped (default 0.005)")
    p.set_defaults(handler=cmd_simulate)


def cmd_simulate(args: argparse.Namespace) -> int:
    if not 1.0 <= args.duration <= 3600:
        raise UserError(f"--duration {args.duration:g}: expected 1 to 3600 seconds")
    if not 0.01 <= args.scale <= 1.0:
        raise UserError(f"--scale {args.scale:g}: expected 0.01 to 1")
    if not 0.0 <= args.drop_probability < 0.5:
        raise UserError(f"--drop-probability {args.drop_probability:g}: expected 0 to 0.5")
    rig = rig_from_args(args)
    from ..sim.writer import simulate    # here: OpenCV, mcap and the scene's geometry load only for this command
    truth = simulate(rig, args.out, SimParams(args.duration, args.seed, args.drop_probability), args.scale)
    if args.json:
        print_json({"out": str(args.out), "truth": truth})
    elif not args.quiet:
        print(args.out / "bag" / "bag_0.mcap")
        print(args.out / "truth.json")
        print(f"{sum(truth['topics'].values())} messages; dropped "
              + ", ".join(f"{c} {len(v)}" for c, v in truth["dropped"].items()))
    return 0
