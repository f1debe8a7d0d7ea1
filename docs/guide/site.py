"""build/docs: the index, the assembly guide (html, md), the BOM, the wiring and printing pages, pictures."""
from __future__ import annotations

from pathlib import Path

from bom.bom import Bom
from bom.render import common_context, environment, write_bom
from docs.guide import pictures, wiring
from docs.guide.steps import Guide, note_context

TEMPLATES = Path(__file__).resolve().parent / "templates"

NAV = [("index.html", "Overview"), ("assembly.html", "Assembly guide"), ("bom.html", "Bill of materials"),
       ("wiring.html", "Wiring"), ("printing.html", "Printing")]


def write_site(asm, bom: Bom, guide: Guide, stage: Path) -> list[Path]:
    env = environment(TEMPLATES)
    rig = asm.rig
    site = dict(nav=NAV)
    files = write_bom(bom, stage, command="docs", site=site, env=env)
    img = stage / "img"
    files += pictures.render_steps(asm, guide.steps, img)
    files += pictures.render_cables(asm, guide.steps, img)
    files += pictures.render_overview(asm, img)
    from cad.electrical import power_counts
    counts = power_counts(asm)
    blocks, wires, checks = wiring.wiring(rig, counts)
    (stage / "wiring.svg").write_text(wiring.svg(rig, counts))
    files.append(stage / "wiring.svg")
    printed = [p for p in bom.made if p.category == "printed"]
    fil = next(ln for ln in bom.lines if ln.source == "printed volumes")
    ctx = common_context(bom, "docs")
    ctx.update(note_context(rig), bom=bom, guide=guide, site=True, nav=NAV, wires=wires, checks=checks,
               printed=printed, printed_mass=sum(p.total_mass_g for p in printed), filament_g=fil.quantity,
               filament_line=fil, filament_m=sum(p.filament_m * p.quantity for p in printed) * fil.quantity
               / max(sum(p.total_mass_g for p in printed), 1e-9),
               sync_source=rig.part(rig.desc.sync.source_part).part_number)
    for name, tpl in (("index.html", "index.html.j2"), ("assembly.html", "assembly.html.j2"),
                      ("assembly.md", "assembly.md.j2"), ("wiring.html", "wiring.html.j2"),
                      ("printing.html", "printing.html.j2")):
        p = stage / name
        p.write_text(env.get_template(tpl).render(ctx, page=name))
        files.append(p)
    return files
