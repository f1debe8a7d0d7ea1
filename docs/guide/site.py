"""build/docs: the index, the assembly guide (html, md), the BOM, the wiring and printing pages, pictures."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Mapping

from bom.bom import Bom
from bom.render import common_context, environment, write_bom
from docs.guide import pictures, wiring
from docs.guide.steps import Guide, note_context

TEMPLATES = Path(__file__).resolve().parent / "templates"

NAV = [("index.html", "Overview"), ("assembly.html", "Assembly guide"), ("bom.html", "Bill of materials"),
       ("wiring.html", "Wiring"), ("printing.html", "Printing")]


@dataclass(frozen=True)
class Supports:
    """One printed part's supports, as the printability check measures them (cad/printability.py analyse,
    the function check "printable without supports" runs) on the part's exported STL in its print
    orientation."""
    part_id: str
    rpy_deg: tuple[float, float, float]   # the print orientation (roll, pitch, yaw), cad PRINT_SETUPS
    orientation: str                      # why that orientation (PrintSetup.why)
    ok: bool                              # no supports needed
    patches: int                          # overhanging patches (faces steeper than the limit)
    overhang_mm2: float
    longest_bridge_mm: float              # the longest bridge of the patches that print (slivers aside)
    places: tuple[str, ...]               # each patch that needs support: where, its size, its span


def supports(asm, results: Mapping | None = None) -> list[Supports]:
    """Per printed part: its orientation and the check's verdict. ``results`` (part id ->
    :class:`cad.printability.Printability`) replaces the check's own run (tests give a patched result)."""
    from cad.assembly import PRINT_SETUPS
    if results is None:
        from cad.checks import printability_of
        results = printability_of(asm)
    return [Supports(pid, tuple(PRINT_SETUPS[pid].rpy_deg), PRINT_SETUPS[pid].why, r.ok, len(r.regions),
                     r.overhang_mm2, r.longest_bridge_mm, tuple(g.describe() for g in r.failing))
            for pid, r in results.items()]


def page_context(asm, bom: Bom, guide: Guide, printability: Mapping | None = None) -> dict:
    """What the pages' templates read: the BOM, the guide, the wiring's wires and checks, the printed parts
    and their supports (:func:`supports`, ``printability`` passed on to it)."""
    rig = asm.rig
    from cad.electrical import power_counts
    counts = power_counts(asm)
    blocks, wires, checks = wiring.wiring(rig, counts)
    printed = [p for p in bom.made if p.category == "printed"]
    fil = next(ln for ln in bom.lines if ln.source == "printed volumes")
    ctx = common_context(bom, "docs")
    ctx.update(note_context(rig), bom=bom, guide=guide, site=True, nav=NAV, wires=wires, checks=checks,
               printed=printed, printed_mass=sum(p.total_mass_g for p in printed), filament_g=fil.quantity,
               filament_line=fil, filament_m=sum(p.filament_m * p.quantity for p in printed) * fil.quantity
               / max(sum(p.total_mass_g for p in printed), 1e-9),
               sync_source=rig.part(rig.desc.sync.source_part).part_number,
               supports=supports(asm, printability))
    return ctx


PAGES = (("index.html", "index.html.j2"), ("assembly.html", "assembly.html.j2"), ("assembly.md", "assembly.md.j2"),
         ("wiring.html", "wiring.html.j2"), ("printing.html", "printing.html.j2"))


def render_page(name: str, ctx: dict, env=None) -> str:
    """One page of :data:`PAGES` rendered from :func:`page_context`'s ``ctx``."""
    env = env or environment(TEMPLATES)
    return env.get_template(dict(PAGES)[name]).render(ctx, page=name)


def write_site(asm, bom: Bom, guide: Guide, stage: Path) -> list[Path]:
    env = environment(TEMPLATES)
    rig = asm.rig
    site = dict(nav=NAV)
    files = write_bom(bom, stage, command="docs", site=site, env=env)
    img = stage / "img"
    meshes: dict = {}                       # each part tessellated once for every picture
    files += pictures.render_steps(asm, guide.steps, img, meshes=meshes)
    files += pictures.render_cables(asm, guide.steps, img, meshes=meshes)
    files += pictures.render_overview(asm, img, meshes=meshes)
    from cad.electrical import power_counts
    (stage / "wiring.svg").write_text(wiring.svg(rig, power_counts(asm)))
    files.append(stage / "wiring.svg")
    ctx = page_context(asm, bom, guide)
    for name, _ in PAGES:
        p = stage / name
        p.write_text(render_page(name, ctx, env))
        files.append(p)
    return files
