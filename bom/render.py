"""Write the BOM (csv, md, html); its jinja2 environment and page base are shared with the assembly guide
(docs.guide), which adds its own templates folder.

Every line says what to order and how far to trust it (:class:`Order`): the maker part with the page its
MPN was read on (a rig part's maker and MPN are its vendor and part number in config/rig.yaml), an MPN not
verified here, a candidate the CAD model cannot hold yet (the line's own part is still the rig's
estimate), a generic part with the reason no MPN was verified (its shop search shown as a search), a
part named by its vendor (as the rig description writes it), or a part made from the CAD model.
"""
from __future__ import annotations

import csv
import io
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping

import jinja2

from .bom import Bom, Line
from .catalogue import is_search_link, read_entries
from .catalogue_schema import CatalogueEntry

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


#: how far to trust what a line says to order, best first
VERIFIED = "MPN verified"                 # maker part number read on the page in ``source``
UNVERIFIED = "MPN not verified"           # a maker part number, its page not read here
CANDIDATE = "candidate: does not fit the CAD model yet"   # chosen, but the rig still describes an estimate
GENERIC = "generic: no MPN verified"      # a description only; ``source`` says why
NAMED = "named by its vendor, not verified here"   # vendor and part number as config/rig.yaml or a supply writes them
MADE = "made from the CAD model"          # printed or machined


@dataclass(frozen=True)
class Order:
    """What one BOM line says to order, and the evidence for it."""
    maker: str
    mpn: str
    status: str       # one of VERIFIED, UNVERIFIED, CANDIDATE, GENERIC, NAMED, MADE
    source: str       # the page the MPN was read on, what an unverified MPN rests on, or why a line is generic
    note: str         # what to check before ordering (a candidate: why it does not fit yet)
    search: bool      # the line's link is a shop search (a generic line only)
    link_read: bool   # the link is the page read for the MPN (as a stored copy); no other link was opened


def order_of(line: Line, entry: CatalogueEntry | None) -> Order:
    """The :class:`Order` of ``line`` from its catalogue ``entry``."""
    search = is_search_link(line.link) if line.link.startswith(("https://", "http://")) else False
    if entry is None or line.vendor == "printed" or entry.made is not None:
        return Order(line.vendor, line.part_number, MADE, "", "", False, False)
    if entry.part is not None:
        p = entry.part
        maker, mpn = p.maker or line.vendor, p.mpn or line.part_number   # a rig part's: config/rig.yaml's
        if p.candidate is not None:
            return Order(maker, mpn, CANDIDATE, p.source, " ".join(filter(None, (p.candidate, p.note))), search,
                         p.verified and line.link == p.source)
        return Order(maker, mpn, VERIFIED if p.verified else UNVERIFIED, p.source, p.note or "", search,
                     p.verified and line.link == p.source)
    if entry.generic is not None:
        return Order("generic", line.part_number, GENERIC, entry.generic, "", search, False)
    return Order(line.vendor, line.part_number, NAMED, "", "", search, False)


def orders(bom: Bom) -> dict[str, Order]:
    """Every line's :class:`Order`, by line key (the catalogue is the one the bill was joined with)."""
    entries: Mapping[str, CatalogueEntry] = read_entries(bom.catalogue_path)
    return {ln.key: order_of(ln, entries.get(ln.entry_id)) for ln in bom.lines}


CSV_FIELDS = ["category", "key", "name", "vendor", "part_number", "supplier", "link", "quantity", "unit", "pack_size",
              "packs", "pack_price", "cost", "currency", "unit_mass_g", "mass_g", "mass_source", "price_note",
              "source", "nodes", "maker", "mpn", "mpn_status", "mpn_source", "order_note", "link_kind"]


def bom_csv(bom: Bom, by_key: Mapping[str, Order] | None = None) -> str:
    by_key = orders(bom) if by_key is None else by_key
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(CSV_FIELDS)
    for ln in bom.lines:
        o = by_key[ln.key]
        row = dict(vars(ln), currency=bom.currency, nodes=" ".join(ln.nodes),
                   pack_price=f"{ln.pack_price:.2f}", cost=f"{ln.cost:.2f}", mass_g=f"{ln.mass_g:.1f}",
                   unit_mass_g="" if ln.unit_mass_g is None else f"{ln.unit_mass_g:g}", quantity=f"{ln.quantity:g}",
                   maker=o.maker, mpn=o.mpn, mpn_status=o.status, mpn_source=o.source, order_note=o.note,
                   link_kind=_link_kind(o))
        w.writerow([row[f] for f in CSV_FIELDS])
    total = dict.fromkeys(CSV_FIELDS, "")
    total.update(category="total", key="total", cost=f"{bom.total_cost:.2f}", currency=bom.currency,
                 mass_g=f"{bom.total_mass_g:.1f}")
    w.writerow([total[f] for f in CSV_FIELDS])
    return buf.getvalue()


def _link_kind(o: Order) -> str:
    """How the CSV describes a line's link."""
    if o.search:
        return "shop search (generic part)"
    return "page read for the MPN (stored copy)" if o.link_read else "not opened here"


def order_counts(by_key: Mapping[str, Order]) -> dict[str, int]:
    """How many lines have each status (the BOM's summary sentence)."""
    return {status: sum(1 for o in by_key.values() if o.status == status)
            for status in (VERIFIED, UNVERIFIED, CANDIDATE, GENERIC, NAMED, MADE)}


def write_bom(bom: Bom, folder: Path, *, command: str = "bom", site: dict | None = None, env=None) -> list[Path]:
    """bom.csv, bom.md, bom.html and style.css into ``folder`` (a staging folder)."""
    env = env or environment()
    by_key = orders(bom)
    ctx = common_context(bom, command)
    ctx.update(bom=bom, node_count=sum(len(ln.nodes) for ln in bom.lines if ln.source == "CAD assembly"),
               site=bool(site), nav=(site or {}).get("nav", []), page="bom.html", orders=by_key,
               order_counts=order_counts(by_key), status=dict(verified=VERIFIED, unverified=UNVERIFIED,
                                                             candidate=CANDIDATE, generic=GENERIC, named=NAMED,
                                                             made=MADE))
    out = []
    for name, text in (("bom.csv", bom_csv(bom, by_key)), ("bom.md", env.get_template("bom.md.j2").render(ctx)),
                       ("bom.html", env.get_template("bom.html.j2").render(ctx)),
                       ("style.css", (TEMPLATES / "style.css").read_text())):
        p = folder / name
        p.write_text(text)
        out.append(p)
    return out
