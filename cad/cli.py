"""The cad commands of `python cad/build.py` (cad/build.py gathers them with the bom and docs ones).

    python cad/build.py export STEP|STL|GLB|SVG|PNG|all [--out DIR] [--set key=value ...]
    python cad/build.py check [--report FILE] [--json]
    python cad/build.py params [--json]

Thin: parse, call the cad modules, print. Exit codes: 0 ok, 1 a check failed, 2 bad input (a bad
--set, an impossible design, an unwritable output folder, an unknown format).
"""
from __future__ import annotations

import sys
from pathlib import Path

from platform_tools.rig.atomic import OutputDir, write_text
from platform_tools.rig.conventions import UserError, add_output_options, add_rig_options, print_json
from platform_tools.rig.conventions import rig_from_args as _load_rig_from_args

DEFAULT_OUT = Path(__file__).resolve().parents[1] / "build" / "cad"


def rig_from_args(args):
    """The rig from the command's options (``--rig``, ``--set``). A ``--set`` the rig loader refuses as
    out of range (it knows a type and a sign) for a key whose real limit the layout sets
    (``cad.layout.constraints.LAYOUT_LIMITS``) is re-phrased with that limit, as a value inside the
    loader's range but outside the layout's is: one line, exit 2."""
    from platform_tools.rig.loader import RigError
    try:
        return _load_rig_from_args(args)
    except RigError as exc:
        lines = with_layout_limits(args, exc.lines)
        if lines == exc.lines:
            raise
        raise RigError(lines) from None


def with_layout_limits(args, lines: list[str]) -> list[str]:
    """``lines`` (the rig loader's problems) with each refused numeric ``--set`` of a key in
    ``LAYOUT_LIMITS`` given the layout's range, read off the layout made from the rig without the
    refused ``--set`` values; ``lines`` as they are when that rig or layout cannot be made."""
    import yaml
    from platform_tools.rig import load_rig
    from cad.layout.constraints import LAYOUT_LIMITS
    from cad.layout.constants import C
    from cad.layout.rig_layout import build_layout
    overrides = list(getattr(args, "overrides", None) or ())
    refused = [o for o in overrides if any(line.startswith(f"--set {o}: ") for line in lines)]
    limited = {}
    for o in refused:
        key, _, raw = o.partition("=")
        key = key.strip()
        try:
            value = yaml.safe_load(raw)
        except yaml.YAMLError:
            continue
        if key in LAYOUT_LIMITS and isinstance(value, (int, float)) and not isinstance(value, bool):
            limited[o] = (key, value)
    if not limited:
        return lines
    try:
        lay = build_layout(load_rig(args.rig, [o for o in overrides if o not in refused]), C)
    except Exception:   # noqa: BLE001 -- only a better message: the loader's own lines stand
        return lines
    out = list(lines)
    for o, (key, value) in limited.items():
        expected = LAYOUT_LIMITS[key](lay)
        if expected is not None:
            out = [f"--set {o}: {key}: got {value:g} mm; {expected}" if line.startswith(f"--set {o}: ") else line
                   for line in out]
    return out


def assembly_from_args(args, rig=None):
    """The assembly from the rig the command's options give (``--rig``, ``--set``, ``--no-cache``); an
    impossible design is bad input (:class:`UserError`, exit 2) naming the rig keys. ``rig``: the rig
    already loaded from these options."""
    from cad.assembly import build
    from cad.cache import ShapeCache
    from cad.layout import DesignError
    rig = rig if rig is not None else rig_from_args(args)
    try:
        return build(rig, ShapeCache(enabled=not args.no_cache))
    except DesignError as exc:
        raise design_error(exc.problems) from None


def checked_rig(args):
    """The rig from the command's options, refused as :func:`rig_from_args` refuses it or as an impossible design
    (:func:`design_error`) before anything loads CadQuery: the layout and its limits are numbers (cad/geom.py), so
    a bad ``--set`` is one line in about a second, not after 3 to 4 s of CadQuery's and OpenCascade's imports."""
    from cad.layout import design_problems
    rig = rig_from_args(args)
    problems = design_problems(rig)
    if problems:
        raise design_error(problems)
    return rig


def design_error(problems) -> UserError:
    """An impossible design as bad input: one line per problem, each naming the rig key and its limit."""
    return UserError("\n".join(str(p) for p in problems))


def replace_refusal(out: Path) -> str | None:
    """Why ``--out`` may not be replaced (one line naming the folder and what in it export did not
    write), or None: ``--out`` never deletes what it did not write."""
    from cad.export_folder import EXPORT_MARKER, foreign_files
    foreign = foreign_files(out)
    if not foreign:
        return None
    names = [f.relative_to(out).as_posix() + ("/" if f.is_dir() and not f.is_symlink() else "") for f in foreign]
    shown = ", ".join(names[:3]) + (f" and {len(names) - 3} more" if len(names) > 3 else "")
    what = ("a previous export, but it also holds" if (Path(out) / EXPORT_MARKER).is_file() else
            "not a previous export: it holds")
    return (f"{out}: {what} {shown}, which export did not write; refusing to replace it (that would delete "
            f"{'it' if len(names) == 1 else 'them'}); move {'it' if len(names) == 1 else 'them'} out or choose "
            f"an empty or new --out folder")


def cmd_export(args) -> int:
    if args.tolerance <= 0 or args.angular_tolerance <= 0:
        raise UserError("--tolerance and --angular-tolerance must be > 0 (mm and radians)")
    from cad.export_folder import FORMATS
    fmt = args.format.upper()
    if fmt != "ALL" and fmt not in FORMATS:
        raise UserError(f"unknown export format {args.format!r}; expected one of {', '.join(FORMATS)} or all")
    formats = set(FORMATS) if fmt == "ALL" else {fmt}
    refusal = replace_refusal(args.out)
    if refusal:
        raise UserError(refusal)
    rig = checked_rig(args)
    from cad.export import export
    asm = assembly_from_args(args, rig)
    with OutputDir(args.out) as stage:
        files = export(asm, stage, formats, args.tolerance, args.angular_tolerance)
        refusal = replace_refusal(args.out)     # something put there while the export ran: the stage goes
        if refusal:
            raise UserError(refusal)
        names = [str(args.out / f.relative_to(stage)) for f in files]
    if args.json:
        print_json({"out": str(args.out), "files": names, "cache": {"hits": asm.cache.hits, "misses": asm.cache.misses}})
    elif not args.quiet:
        print("\n".join(names))
    return 0


def cmd_check(args) -> int:
    rig = checked_rig(args)
    from cad.checks import report, run_checks
    results = run_checks(assembly_from_args(args, rig))
    text = report(results, verbose=args.verbose > 0)
    if args.report:
        write_text(args.report, text)
    if args.json:
        print_json([dict(name=r.name, ok=r.ok, summary=r.summary, details=r.details) for r in results])
    elif not args.quiet:
        sys.stdout.write(text)
    return 0 if all(r.ok for r in results) else 1


def cmd_params(args) -> int:
    from cad.layout import C, DesignError, layout
    rig = rig_from_args(args)
    try:
        lay = layout(rig) if not args.rig_only else None
    except DesignError as exc:
        raise design_error(exc.problems) from None
    doc = {"rig": rig.to_data(), "rig_hash": rig.hash, "overrides": list(rig.overrides)}
    if lay is not None:
        from cad.bought.base import provenance
        doc["vendor_dimensions"] = [vars(r) for pid in rig.desc.parts for r in provenance(rig, pid)]
        doc["design_constants"] = dict(vars(C))
        doc["derived"] = {
            "case_outer_mm": {"lo": lay.case.outer.lo, "hi": lay.case.outer.hi, "size": lay.case.outer.size},
            "case_split_z_mm": lay.case.split_z,
            "orin_standoff_mm": lay.compute.standoff_h,
            "vent_slots": len(lay.case.vents),
            "joints": len(lay.joints),
            "screws": {j.name: f"{j.thread} x {j.length_mm:g}" for j in lay.joints},
        }
    import json
    doc = json.loads(json.dumps(doc, default=lambda v: float(v) if hasattr(v, "__float__") else str(v)))
    if args.json:
        print_json(doc)
        return 0
    import yaml
    sys.stdout.write(yaml.safe_dump(doc, sort_keys=False, default_flow_style=None, width=110))
    return 0


def register(sub) -> None:
    """Add the `export`, `check` and `params` commands to cad/build.py's sub-command parser."""
    e = sub.add_parser("export", help="write STEP, STL, GLB, SVG, PNG (or all) to --out",
                       description="Export the assembly (one STEP with named, coloured parts; a GLB), every printed "
                                   "part as STEP and STL in its print orientation, and SVG/PNG views. The output "
                                   "folder is replaced whole, only when everything was written, and only if it is empty "
                                   "or holds nothing but a previous export (the files its manifest lists).",
                       epilog="Exit codes: 0 written; 2 bad input (a bad --set, an impossible design, an unknown "
                              "format, an --out folder holding anything a previous export did not write, or one that cannot be "
                              "written).")
    e.add_argument("format", metavar="FORMAT", help="STEP, STL, GLB, SVG, PNG or all")
    e.add_argument("--out", type=Path, default=DEFAULT_OUT, help="output folder (default: build/cad)")
    e.add_argument("--tolerance", type=float, default=0.1, help="mesh linear tolerance for STL/GLB/PNG (mm)")
    e.add_argument("--angular-tolerance", type=float, default=0.2, help="mesh angular tolerance (radians)")
    e.add_argument("--no-cache", action="store_true", help="rebuild every part (ignore the build cache)")
    add_rig_options(e)
    add_output_options(e)
    e.set_defaults(handler=cmd_export)

    c = sub.add_parser("check", help="check the assembly; exit 1 with a report if anything fails",
                       description="Valid solids, interference (intended overlaps measured), minimum wall, heat sink "
                                   "/ fan / wall clearances, print bed, fields of view, battery removal, vent area, "
                                   "camera datums (each camera held in 6 DOF by named features, with its tolerance "
                                   "stack-up), mass and balance, grip span, standing on a table, record button reach, "
                                   "and the list of estimates.",
                       epilog="Exit codes: 0 every check passed; 1 a check failed (the report says which); 2 bad "
                              "input (a bad --set or an impossible design: one line per rig key, with its limit).")
    c.add_argument("--report", type=Path, help="also write the report to this file")
    c.add_argument("--no-cache", action="store_true", help="rebuild every part (ignore the build cache)")
    add_rig_options(c)
    add_output_options(c)
    c.set_defaults(handler=cmd_check)

    r = sub.add_parser("params", help="every resolved parameter (rig values, design constants, derived sizes)",
                       description="Print the resolved rig description, the design's own constants and derived sizes.",
                       epilog="Exit codes: 0 printed; 2 bad input (a bad --set or an impossible design).")
    r.add_argument("--rig-only", action="store_true", help="only the rig description (no layout)")
    add_rig_options(r)
    add_output_options(r)
    r.set_defaults(handler=cmd_params)
