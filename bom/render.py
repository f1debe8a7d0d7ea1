"""Write the BOM (csv, md, html); its jinja2 environment and page base are shared with the assembly guide
(docs.guide), which adds its own templates folder."""
from __future__ import annotations

import csv
import io
import re
from pathlib import Path

import jinja2

from .bom import Bom

TEMPLATES = Path(__file__).resolve().parent / "templates"


def environment(*template_dirs: Path) -> jinja2.Environment:
    """The BOM's templates (bom/templates: the page base, the BOM tables, the style sheet), after any
    ``template_dirs`` (searched first)."""
    search = [str(d) for d in template_dirs] + [str(TEMPLATES)]
    env = jinja2.Environment(loader=jinja2.FileSystemLoader(search), undefined=jinja2.StrictUndefined,
                             autoescape=jinja2.select_autoescape(enabled_extensions=("html.j2", "html"),
                                                                 default_for_string=False),
                             trim_blocks=False, lstrip_blocks=False, keep_trailing_newline=True,
                             finalize=lambda v: f"{v:.6g}" if isinstance(v, float) else v)
    env.filters["money"] = lambda v: f"{v:,.2f}"
    env.filters["slug"] = lambda v: re.sub(r"[^a-z0-9]+", "-", str(v).lower()).strip("-")
    env.filters["mdcell"] = lambda v: str(v).replace("|", "\\|").replace("\n", " ")
    return env


def common_context(bom: Bom, command: str) -> dict:
    return dict(rig_name=bom.rig_name, rig_hash=bom.rig_hash, overrides=list(bom.overrides), command=command,
                catalogue_name=_short(bom.catalogue_path))


def _short(path: str) -> str:
    p = Path(path)
    try:
        return str(p.resolve().relative_to(Path(__file__).resolve().parents[1]))
    except ValueError:
        return str(p)


CSV_FIELDS = ["category", "key", "name", "vendor", "part_number", "supplier", "link", "quantity", "unit", "pack_size",
              "packs", "pack_price", "cost", "currency", "unit_mass_g", "mass_g", "mass_source", "price_note",
              "source", "nodes"]


def bom_csv(bom: Bom) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(CSV_FIELDS)
    for ln in bom.lines:
        row = dict(vars(ln), currency=bom.currency, nodes=" ".join(ln.nodes),
                   pack_price=f"{ln.pack_price:.2f}", cost=f"{ln.cost:.2f}", mass_g=f"{ln.mass_g:.1f}",
                   unit_mass_g="" if ln.unit_mass_g is None else f"{ln.unit_mass_g:g}", quantity=f"{ln.quantity:g}")
        w.writerow([row[f] for f in CSV_FIELDS])
    w.writerow(["total", "total", "", "", "", "", "", "", "", "", "", "", f"{bom.total_cost:.2f}", bom.currency, "",
                f"{bom.total_mass_g:.1f}", "", "", "", ""])
    return buf.getvalue()


def write_bom(bom: Bom, folder: Path, *, command: str = "bom", site: dict | None = None, env=None) -> list[Path]:
    """bom.csv, bom.md, bom.html and style.css into ``folder`` (a staging folder)."""
    env = env or environment()
    ctx = common_context(bom, command)
    ctx.update(bom=bom, node_count=sum(len(ln.nodes) for ln in bom.lines if ln.source == "CAD assembly"),
               site=bool(site), nav=(site or {}).get("nav", []), page="bom.html")
    out = []
    for name, text in (("bom.csv", bom_csv(bom)), ("bom.md", env.get_template("bom.md.j2").render(ctx)),
                       ("bom.html", env.get_template("bom.html.j2").render(ctx)),
                       ("style.css", (TEMPLATES / "style.css").read_text())):
        p = folder / name
        p.write_text(text)
        out.append(p)
    return out
