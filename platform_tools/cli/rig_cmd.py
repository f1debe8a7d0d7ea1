"""`platform_tools rig ...`: show, validate, list estimates and export the rig description."""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import yaml

from platform_tools.rig import atomic
from ..rig import Rig, RigError, frames_table, load_rig
from platform_tools.rig.conventions import (EXIT_BAD_INPUT, add_output_options, add_rig_options, print_json,
    rig_from_args)


def register(sub: argparse._SubParsersAction) -> None:
    rig = sub.add_parser("rig", help="the rig description (config/rig.yaml)",
                         description="Show, validate and export the rig description.")
    rsub = rig.add_subparsers(title="rig commands", metavar="ACTION")

    p = rsub.add_parser("show", help="print every resolved value and the derived sensor frames",
                        description="Print the rig description after overrides, with derived values: "
                                    "sensor frames in the rig frame, nominal focal lengths, the estimates count.")
    add_rig_options(p)
    add_output_options(p)
    p.add_argument("--section", metavar="KEY", help="print only this top-level section, e.g. sensors")
    p.set_defaults(handler=cmd_show)

    p = rsub.add_parser("validate", help="check a rig file; one line per problem, exit 2 if any",
                        description="Validate a rig description file: types, units, ranges, references and "
                                    "physical rules. Prints one line per problem naming the file, line and key.")
    p.add_argument("file", metavar="FILE", help="the rig description to check")
    p.add_argument("--set", metavar="KEY=VALUE", action="append", default=[], dest="overrides",
                   help="validate with these overrides applied")
    add_output_options(p)
    p.set_defaults(handler=cmd_validate)

    p = rsub.add_parser("estimates", help="list every vendor number that is only an estimate",
                        description="Every dimension, mass or power that is an estimate, with its key path: "
                                    "the measurements still to make on real parts.")
    add_rig_options(p)
    add_output_options(p)
    p.set_defaults(handler=cmd_estimates)

    p = rsub.add_parser("export", help="write the resolved description and sensor frames to a folder",
                        description="Write rig.resolved.yaml, rig.resolved.json and frames.vnl "
                                    "(a vnlog of every sensor frame in the rig frame) to --out.")
    add_rig_options(p)
    add_output_options(p, json_output=False)
    p.add_argument("--out", metavar="DIR", required=True, type=Path, help="output folder (replaced whole)")
    p.set_defaults(handler=cmd_export)


def derived(rig: Rig) -> dict:
    cams = {}
    for name, m in rig.desc.camera_models.items():
        cams[name] = {"focal_px": rig.focal_px(m), "hfov_from_focal_deg": rig.hfov_from_focal_deg(m)}
    return {
        "rig_file": str(rig.path),
        "overrides": list(rig.overrides),
        "hash": rig.hash,
        "frames": frames_table(rig),
        "camera_models": cams,
        "thermal_module_width_mm": rig.thermal_module_width_mm(),
        "estimates": len(rig.estimates()),
    }


def cmd_show(args: argparse.Namespace) -> int:
    rig = rig_from_args(args)
    data = rig.to_data()
    if args.section:
        if args.section not in data:
            from platform_tools.rig.conventions import UserError
            raise UserError(f"--section {args.section}: no such section; the rig has {', '.join(data)}")
        data = {args.section: data[args.section]}
    doc = {"rig": data, "derived": derived(rig)}
    if args.json:
        print_json(doc)
        return 0
    yaml.safe_dump(data, sys.stdout, sort_keys=False, default_flow_style=None, width=110)
    d = doc["derived"]
    print(f"\n# derived from {d['rig_file']}" + (f" with {' '.join(d['overrides'])}" if d["overrides"] else ""))
    print(f"# hash {d['hash']}")
    print("# sensor frames in the rig frame (x forward, y left, z up; mm, URDF roll-pitch-yaw deg)")
    print(f"#   {'frame':22s} {'x':>8s} {'y':>8s} {'z':>8s} {'roll':>8s} {'pitch':>8s} {'yaw':>8s}")
    for f in d["frames"]:
        print(f"#   {f['frame']:22s} {f['x_mm']:8.2f} {f['y_mm']:8.2f} {f['z_mm']:8.2f} "
              f"{f['roll_deg']:8.2f} {f['pitch_deg']:8.2f} {f['yaw_deg']:8.2f}")
    for name, c in d["camera_models"].items():
        print(f"# {name}: nominal focal {c['focal_px']:.1f} px (HFoV {c['hfov_from_focal_deg']:.1f} deg from it)")
    print(f"# one Boson with its heat sink is {d['thermal_module_width_mm']:g} mm wide")
    print(f"# {d['estimates']} values are estimates: platform_tools rig estimates")
    return 0


def cmd_validate(args: argparse.Namespace) -> int:
    try:
        rig = load_rig(args.file, args.overrides)
    except RigError as exc:
        if args.json:
            print_json({"file": args.file, "valid": False, "errors": exc.lines})
        raise
    n = len(rig.estimates())
    if args.json:
        print_json({"file": args.file, "valid": True, "hash": rig.hash, "estimates": n})
    elif not args.quiet:
        print(f"{args.file}: valid (hash {rig.hash[:12]}; {n} values are estimates)")
    return 0


def cmd_estimates(args: argparse.Namespace) -> int:
    rig = rig_from_args(args)
    rows = [dict(path=e.path, value=e.value, source=e.source, note=e.note) for e in rig.estimates()]
    if args.json:
        print_json(rows)
        return 0
    for r in rows:
        note = f"  ({r['note']})" if r["note"] else ""
        print(f"{r['path']:55s} {r['value']:>9g}{note}")
    print(f"{len(rows)} estimates: measure them on real parts and update {rig.path}", file=sys.stderr)
    return 0


def frames_vnlog(rig: Rig) -> str:
    cols = ["frame", "parent", "x_mm", "y_mm", "z_mm", "qx", "qy", "qz", "qw", "roll_deg", "pitch_deg", "yaw_deg"]
    lines = [f"## sensor frames of rig {rig.desc.name} in the rig frame (x forward, y left, z up), hash {rig.hash}",
             "## q: quaternion x y z w of the frame's orientation; rpy: URDF roll-pitch-yaw",
             "# " + " ".join(cols)]
    for row in frames_table(rig):
        lines.append(" ".join(row[c] if isinstance(row[c], str) else f"{row[c]:.6f}" for c in cols))
    return "\n".join(lines) + "\n"


def cmd_export(args: argparse.Namespace) -> int:
    rig = rig_from_args(args)
    doc = {"rig": rig.to_data(), "derived": derived(rig)}
    with atomic.OutputDir(args.out) as stage:
        (stage / "rig.resolved.yaml").write_text(yaml.safe_dump(doc["rig"], sort_keys=False, width=110))
        (stage / "rig.resolved.json").write_text(json.dumps(doc, indent=2, default=str) + "\n")
        (stage / "frames.vnl").write_text(frames_vnlog(rig))
    if not args.quiet:
        for name in ("rig.resolved.yaml", "rig.resolved.json", "frames.vnl"):
            print(args.out / name)
    return 0
