"""`python cad/build.py bom` (gathered by cad/build.py).

    python cad/build.py bom [--out DIR] [--catalogue FILE] [--set key=value ...]   (default build/bom)

Exit 0 ok, 2 bad input: a malformed catalogue, a part the assembly places with no catalogue entry, a
catalogue entry used nowhere; every problem one line naming the file, its line and the entry. Every
check runs before anything is written, and the output folder is swapped in whole
(platform_tools.rig.atomic.OutputDir): a failed run leaves the previous output as it was.
"""
from __future__ import annotations

import argparse
from pathlib import Path

from platform_tools.rig.atomic import OutputDir
from platform_tools.rig.conventions import add_output_options, add_rig_options, print_json

REPO = Path(__file__).resolve().parents[1]


def assembly_and_bom(args):
    """The CAD assembly of the command's rig and its bill, joined with ``--catalogue``. A bad catalogue
    (InputProblems) or an impossible design (UserError) is bad input: exit 2."""
    from cad.cli import assembly_from_args
    from platform_tools.rig.conventions import rig_from_args

    from .bom import build_bom
    from .catalogue import load_catalogue
    rig = rig_from_args(args)
    cat = load_catalogue(rig, args.catalogue)   # checked before any geometry
    asm = assembly_from_args(args, rig)
    return asm, build_bom(asm, cat)


def report(args, out: Path, files: list[Path], stage: Path, bom, extra: dict | None = None) -> None:
    """Print what was written (or one JSON document with ``--json``) and the bill's totals."""
    names = sorted(str(out / f.relative_to(stage)) for f in files)
    if args.json:
        print_json(dict(out=str(out), files=names, total_cost=round(bom.total_cost, 2), currency=bom.currency,
                        total_mass_g=round(bom.total_mass_g, 1), **(extra or {})))
    elif not args.quiet:
        print("\n".join(names))
        print(f"total {bom.total_cost:,.2f} {bom.currency}, {bom.total_mass_g / 1000:.2f} kg, {len(bom.lines)} lines")


def cmd_bom(args) -> int:
    from .render import write_bom
    _, bom = assembly_and_bom(args)
    with OutputDir(args.out) as stage:
        files = write_bom(bom, stage)
    report(args, args.out, files, stage, bom)
    return 0


def register(sub) -> None:
    """Add the `bom` command to cad/build.py's sub-command parser."""
    b = sub.add_parser("bom", help="bill of materials from the CAD assembly and bom/parts.yaml (csv, md, html)",
                       description="Walk the CAD assembly, join the catalogue (bom/parts.yaml) and write bom.csv, "
                                   "bom.md and bom.html: grouped by category, subtotals, total cost and mass, "
                                   "links, and the printed and machined parts. Exit 2 naming the part when the "
                                   "assembly places a part with no catalogue entry or an entry is used nowhere.")
    b.add_argument("--out", type=Path, default=REPO / "build" / "bom", help="output folder (default: build/bom)")
    add_bom_options(b)
    b.set_defaults(handler=cmd_bom)


def add_bom_options(p: argparse.ArgumentParser) -> None:
    """The options of every command that builds the bill: catalogue, cache, rig and output."""
    p.add_argument("--catalogue", type=Path, default=None, help="catalogue (default: bom/parts.yaml)")
    p.add_argument("--no-cache", action="store_true", help="rebuild every part (ignore the build cache)")
    add_rig_options(p)
    add_output_options(p)
