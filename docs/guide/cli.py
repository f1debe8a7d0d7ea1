"""`python cad/build.py docs` (gathered by cad/build.py): the assembly guide, BOM, wiring and printing
pages under build/docs.

    python cad/build.py docs [--out DIR] [--catalogue FILE] [--steps FILE] [--set ...] (default build/docs)

Exit 0 ok, 2 bad input: everything `bom` rejects, a malformed steps file, a step naming an unknown
node, a BOM line no step uses; every problem one line naming the file, its line and the entry. Every
check runs before anything is written; the output folder is swapped in whole.
"""
from __future__ import annotations

from pathlib import Path

from bom.cli import add_bom_options, assembly_and_bom, report
from platform_tools.rig.atomic import OutputDir

REPO = Path(__file__).resolve().parents[2]


def cmd_docs(args) -> int:
    from .site import write_site
    from .steps import load_guide
    asm, bom = assembly_and_bom(args)
    guide = load_guide(asm, bom, args.steps)
    with OutputDir(args.out) as stage:
        files = write_site(asm, bom, guide, stage)
    report(args, args.out, files, stage, bom, dict(steps=len(guide.steps)))
    return 0


def register(sub) -> None:
    """Add the `docs` command to cad/build.py's sub-command parser."""
    d = sub.add_parser("docs", help="assembly guide, BOM, wiring and printing pages (build/docs/index.html)",
                       description="Render docs/assembly/steps.yaml against the CAD assembly into assembly.html "
                                   "and assembly.md with a picture per step, the BOM, a wiring diagram, a printing "
                                   "page and an index. Exit 2 when a step names an unknown node or a BOM line is "
                                   "used by no step.")
    d.add_argument("--out", type=Path, default=REPO / "build" / "docs", help="output folder (default: build/docs)")
    d.add_argument("--steps", type=Path, default=None, help="steps file (default: docs/assembly/steps.yaml)")
    add_bom_options(d)
    d.set_defaults(handler=cmd_docs)
