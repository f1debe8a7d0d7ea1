"""`calibrate extrinsics --from-cad`: every camera's optical frame and the IMU in the rig frame, from
the CAD assembly's placements, in every format robots read (docs/extrinsics.md)."""
from __future__ import annotations

import argparse
from pathlib import Path

from platform_tools.rig import atomic
from platform_tools.rig.conventions import (UserError, add_output_options, add_rig_options, print_json,
    rig_from_args)

DEFAULT_OUT = Path("build/calibration/extrinsics")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "extrinsics", help="extrinsics from the CAD model (URDF, Kalibr, mrcal, ROS 2 launch, YAML)",
        description="Write the pose of every camera optical frame (ZED X left/right, thermal left/right) and "
                    "the ZED IMU in the rig frame, read from the CAD assembly's placements: extrinsics.yaml "
                    "(every pair, convention spelled out), kalibr_camchain.yaml, rig.urdf, "
                    "static_transforms.launch.xml (ROS 2) and one .cameramodel per camera (nominal lens).",
        epilog="Exit codes: 0 ok, 2 bad input (a rig whose cameras overlap, a bad --set).")
    p.add_argument("--from-cad", action="store_true", required=True,
                   help="take the extrinsics from the CAD model (the only source for now; `calibrate rig` "
                        "refines them from images)")
    p.add_argument("--out", type=Path, default=DEFAULT_OUT, metavar="DIR",
                   help=f"output folder, replaced whole (default {DEFAULT_OUT})")
    add_rig_options(p)
    add_output_options(p)
    p.set_defaults(handler=cmd_extrinsics)


def frames_or_user_error(rig):
    from calibration.extrinsics.cad import RigGeometryError, cad_frames
    try:
        return cad_frames(rig)
    except RigGeometryError as exc:
        raise UserError(exc.problems[0] + (f" (and {len(exc.problems) - 1} more)" if len(exc.problems) > 1 else ""))


def cmd_extrinsics(args: argparse.Namespace) -> int:
    from calibration.extrinsics.cad import CAMERAS, IMU
    from calibration.extrinsics.outputs import all_files, nominal_lenses
    rig = rig_from_args(args)
    tree = frames_or_user_error(rig)
    files = all_files(tree, nominal_lenses(rig), rig, source="CAD model (cad.assembly placements)")
    with atomic.OutputDir(args.out) as stage:
        for name, text in files.items():
            (stage / name).write_text(text)
    summary = {"out": str(args.out), "files": sorted(files), "rig_hash": rig.hash,
               "frames": {n: {"xyz_mm": [round(float(x), 6) for x in tree.T_rig[n].t],
                              "rpy_deg": [round(float(x), 6) for x in tree.T_rig[n].rpy_deg()]}
                          for n in list(CAMERAS.values()) + [IMU]}}
    if args.json:
        print_json(summary)
    elif not args.quiet:
        print(f"{args.out}: CAD extrinsics of {len(CAMERAS)} cameras and the IMU ({', '.join(sorted(files))})")
        for n, f in summary["frames"].items():
            x, y, z = f["xyz_mm"]
            print(f"  {n:22s} xyz {x:8.2f} {y:8.2f} {z:8.2f} mm  rpy {' '.join(f'{a:8.3f}' for a in f['rpy_deg'])} deg")
    return 0
