"""`calibrate nominal`: write the nominal .cameramodel of every camera from the rig description."""
from __future__ import annotations

import argparse
import io
from pathlib import Path

from platform_tools.rig import atomic
from platform_tools.rig.conventions import add_output_options, add_rig_options, print_json, rig_from_args

from platform_tools.rig.nominal import nominal_cameras


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("nominal", help="nominal camera models (.cameramodel) from the rig description",
                       description="Write one mrcal .cameramodel per camera (ZED X left/right, thermal "
                                   "left/right): the nominal lens from the rig description, the pose from "
                                   "the rig frame (metres). A seed for calibration, not a calibration.")
    add_rig_options(p)
    add_output_options(p)
    p.add_argument("--out", metavar="DIR", required=True, type=Path, help="output folder (replaced whole)")
    p.set_defaults(handler=cmd_nominal)


def cmd_nominal(args: argparse.Namespace) -> int:
    rig = rig_from_args(args)
    cams = nominal_cameras(rig)
    written = []
    with atomic.OutputDir(args.out) as stage:
        for frame, model in cams.items():
            buf = io.StringIO()
            model.write(buf, note=f"nominal model of {frame} from rig {rig.desc.name} (hash {rig.hash[:12]})")
            name = f"{frame.removesuffix('_optical')}.cameramodel"
            (stage / name).write_text(buf.getvalue())
            lensmodel, intrinsics = model.intrinsics()
            written.append(dict(camera=frame, file=str(args.out / name), lensmodel=lensmodel,
                                intrinsics=intrinsics.tolist(), imagersize=[int(x) for x in model.imagersize()]))
    if args.json:
        print_json(written)
    elif not args.quiet:
        for w in written:
            print(w["file"])
    return 0
