"""`python cad/build.py bom` and `python cad/build.py docs` (registered in cad/build.py).

    python cad/build.py bom  [--out DIR] [--catalogue FILE] [--set key=value ...]   (default build/bom)
    python cad/build.py docs [--out DIR] [--catalogue FILE] [--steps FILE] [--set ...] (default build/docs)

Exit 0 ok, 2 bad input: a malformed catalogue or steps file, a part the assembly places with no
catalogue entry, a catalogue entry used nowhere, a step naming an unknown node, a BOM line no step uses;
every problem one line naming the file, its line and the entry. Every check runs before anything is
written, and the output folder is swapped in whole (platform_tools.rig.atomic.OutputDir): a failed run
leaves the previous output as it was.
"""
from __future__ import annotations

import argparse
from pathlib import Path

from platform_tools.rig.atomic import OutputDir
from platform_tools.rig.conventions import (UserError, add_output_options, add_rig_options, print_json,
    rig_from_args)

REPO = Path(__file__).resolve().parents[1]


def _inputs(args, *, guide: bool):
    from cad.assembly import build
    from cad.cache import ShapeCache
    from cad.design import DesignError

    from .bom import build_bom
    from .catalogue import load_catalogue
    from .guide import load_guide
    rig = rig_from_args(args)
    cat = load_catalogue(rig, args.catalogue)   # bad input (InputProblems) is printed by run(), exit 2
    try:
        asm = build(rig, ShapeCache(enabled=not args.no_cache))
    except DesignError as exc:
        raise UserError("the design cannot be built from these values:\n" + "\n".join(str(p) for p in exc.problems)) from None
    bom = build_bom(asm, cat)
    g = load_guide(asm, bom, args.steps) if guide else None
    return asm, bom, g


def _report(args, out: Path, files: list[Path], stage: Path, bom, extra: dict | None = None) -> None:
    names = sorted(str(out / f.relative_to(stage)) for f in files)
    if args.json:
        print_json(dict(out=str(out), files=names, total_cost=round(bom.total_cost, 2), currency=bom.currency,
                        total_mass_g=round(bom.total_mass_g, 1), **(extra or {})))
    elif not args.quiet:
        print("\n".join(names))
        print(f"total {bom.total_cost:,.2f} {bom.currency}, {bom.total_mass_g / 1000:.2f} kg, {len(bom.lines)} lines")


def cmd_bom(args) -> int:
    from .render import write_bom
    _, bom, _ = _inputs(args, guide=False)
    with OutputDir(args.out) as stage:
        files = write_bom(bom, stage)
    _report(args, args.out, files, stage, bom)
    return 0


def cmd_docs(args) -> int:
    from .site import write_site
    asm, bom, guide = _inputs(args, guide=True)
    with OutputDir(args.out) as stage:
        files = write_site(asm, bom, guide, stage)
    _report(args, args.out, files, stage, bom, dict(steps=len(guide.steps)))
    return 0


def register(sub) -> None:
    """Add the `bom` and `docs` commands to cad/build.py's sub-command parser."""
    b = sub.add_parser("bom", help="bill of materials from the CAD assembly and bom/parts.yaml (csv, md, html)",
                       description="Walk the CAD assembly, join the catalogue (bom/parts.yaml) and write bom.csv, "
                                   "bom.md and bom.html: grouped by category, subtotals, total cost and mass, "
                                   "links, and the printed and machined parts. Exit 2 naming the part when the "
                                   "assembly places a part with no catalogue entry or an entry is used nowhere.")
    b.add_argument("--out", type=Path, default=REPO / "build" / "bom", help="output folder (default: build/bom)")
    _common(b)
    b.set_defaults(handler=cmd_bom)
    d = sub.add_parser("docs", help="assembly guide, BOM, wiring and printing pages (build/docs/index.html)",
                       description="Render docs/assembly/steps.yaml against the CAD assembly into assembly.html "
                                   "and assembly.md with a picture per step, the BOM, a wiring diagram, a printing "
                                   "page and an index. Exit 2 when a step names an unknown node or a BOM line is "
                                   "used by no step.")
    d.add_argument("--out", type=Path, default=REPO / "build" / "docs", help="output folder (default: build/docs)")
    d.add_argument("--steps", type=Path, default=None, help="steps file (default: docs/assembly/steps.yaml)")
    _common(d)
    d.set_defaults(handler=cmd_docs)


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument("--catalogue", type=Path, default=None, help="catalogue (default: bom/parts.yaml)")
    p.add_argument("--no-cache", action="store_true", help="rebuild every part (ignore the build cache)")
    add_rig_options(p)
    add_output_options(p)
