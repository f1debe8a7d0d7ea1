"""Load and check bom/parts.yaml against the rig description.

Every problem is one line naming the file, the line and the entry, as the rig loader does:
``bom/parts.yaml:42: parts.zed_x.price.currency: got 'US$' ...``.

Besides prices and quantities it checks what is to be ordered (:func:`_purchase_rules`): a shop search is
no product, so only an entry marked ``generic`` (no MPN verified) may link to one; a "generic" vendor
needs a maker part or that mark; a maker part says where its MPN was read; a rig part's maker and MPN are
said once, in config/rig.yaml, unless the part is a candidate the CAD model cannot hold yet
(:func:`_identity_rules`); and a part's ratings, copied from that page, are at least what config/rig.yaml
assumes of it (:func:`_rating_rules`).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Iterator, Mapping
from urllib.parse import parse_qs, urlsplit

from platform_tools.rig.problems import InputProblems
from platform_tools.rig import Rig
from platform_tools.rig.typed import Problem, closest, convert
from platform_tools.rig.yamlsource import YamlSource, load_typed

from .catalogue_schema import Catalogue, CatalogueEntry, MakerPart

DEFAULT_CATALOGUE = Path(__file__).resolve().parent / "parts.yaml"
#: query keys that make a link a shop's search results rather than a product page (amazon ?k=,
#: McMaster-Carr ?s=, WAGO ?text=, the common ?q=)
SEARCH_KEYS = frozenset({"k", "q", "s", "text", "search", "keyword", "keywords", "query"})
#: how an unverified MPN's source must begin, so that no reader takes it for a page that was read
UNVERIFIED = "not verified here"


class CatalogueError(InputProblems):
    """bom/parts.yaml is not valid: one line per problem."""


@dataclass(frozen=True)
class LoadedCatalogue:
    catalogue: Catalogue
    source: YamlSource

    @property
    def path(self) -> Path:
        return self.source.path

    @property
    def entries(self):
        return self.catalogue.parts

    def where(self, part_id: str) -> str:
        return self.source.where(("parts", part_id))

    def unit_price(self, entry: CatalogueEntry) -> float:
        """Price of one unit in the base currency."""
        if entry.price is None:
            return 0.0
        rate = 1.0 if entry.price.currency == self.catalogue.base_currency else \
            self.catalogue.exchange_rates[entry.price.currency]
        return entry.price.amount * rate / entry.pack_size


def load_catalogue(rig: Rig, path: Path | str | None = None) -> LoadedCatalogue:
    path = Path(path) if path is not None else DEFAULT_CATALOGUE
    typed = load_typed(path, Catalogue, CatalogueError,
                       rules=lambda cat: [*_rules(cat, rig), *_purchase_rules(cat, rig)])
    return LoadedCatalogue(typed.value, typed.source)


def read_entries(path: Path | str) -> Mapping[str, CatalogueEntry]:
    """The entries of a catalogue already checked against its rig (the BOM's own), by id: what the
    outputs show of each line's maker part."""
    return load_typed(path, Catalogue, CatalogueError).value.parts


def is_search_link(link: str) -> bool:
    """True when ``link`` is a shop's search results (a query such as ``?k=`` or a ``/search`` path)."""
    parts = urlsplit(link)
    return bool(SEARCH_KEYS & set(parse_qs(parts.query))) or "/search" in parts.path.lower()


def _rules(cat: Catalogue, rig: Rig) -> Iterator[Problem]:
    rig_parts = rig.desc.parts
    for cur in cat.exchange_rates:
        if cur == cat.base_currency:
            yield Problem(("exchange_rates", cur), f"is the base currency; it needs no rate")
    seen_numbers: dict[str, str] = {}
    for pid, e in cat.parts.items():
        path = ("parts", pid)
        if e.included_with is not None:
            if e.included_with not in cat.parts or e.included_with == pid:
                yield Problem(path + ("included_with",), f"is {e.included_with!r}, which is not another entry of the "
                                                         "catalogue")
            if e.price is not None:
                yield Problem(path + ("price",), f"comes fitted to {e.included_with} (included_with), which is priced "
                                                 "with it; remove the price")
        elif e.price is None:
            yield Problem(path + ("price",), "is missing; give amount, currency, checked and confidence (or "
                                             "included_with for a part sold fitted to another)")
        if e.price is not None and e.price.currency != cat.base_currency and e.price.currency not in cat.exchange_rates:
            yield Problem(path + ("price", "currency"),
                          f"is {e.price.currency}, which has no rate in exchange_rates (base {cat.base_currency})")
        if not e.link.startswith(("https://", "http://")):
            yield Problem(path + ("link",), f"is {e.link!r}; expected a web address starting with https://")
        fields = _link_fields(e.link)
        if fields - {"thread", "length_mm"}:
            yield Problem(path + ("link",), f"uses {{{sorted(fields - {'thread', 'length_mm'})[0]}}}; a link may only "
                                            "use {thread} and {length_mm} (one link per fastener length)")
        if e.made is not None:
            if pid in rig_parts:
                yield Problem(path + ("made",), f"{pid} is a bought part of the rig description; remove made")
            if e.supply is not None or not e.in_cad:
                yield Problem(path, "is made from the CAD model (made: machined); remove supply and in_cad: false")
            continue
        if pid in rig_parts:
            if e.supply is not None:
                yield Problem(path + ("supply",), f"{pid} is a part of the rig description, which already says "
                                                  f"what it is; remove supply (and keep in_cad: true)")
            if not e.in_cad:
                yield Problem(path + ("in_cad",), f"{pid} is placed by the CAD model; expected in_cad: true")
            number = rig_parts[pid].part_number
        else:
            if e.in_cad:
                hint = closest(pid, rig_parts)
                yield Problem(path, f"is not a part of the rig description"
                                    + (f" (did you mean {hint!r}?)" if hint else "")
                                    + "; a part the CAD model does not place needs in_cad: false and supply")
                continue
            if e.supply is None:
                yield Problem(path + ("supply",), "is missing; a part not in the CAD model must declare vendor, "
                                                  "part number, mass, quantity and why it is needed")
                continue
            number = e.supply.part_number
            yield from _supply_rules(e, path, rig)
        if number in seen_numbers:
            yield Problem(path, f"has part number {number!r}, already used by parts.{seen_numbers[number]}")
        seen_numbers[number] = pid


def _link_fields(link: str) -> set[str]:
    import string
    try:
        return {f for _, f, _, _ in string.Formatter().parse(link) if f is not None}
    except ValueError:
        return {"(unbalanced brace)"}


def _supply_rules(e: CatalogueEntry, path: tuple, rig: Rig) -> Iterator[Problem]:
    s = e.supply
    sp = path + ("supply",)
    if s.quantity_from is None:
        if s.quantity is None:
            yield Problem(sp + ("quantity",), "is missing; give a quantity per rig (or quantity_from: printed_parts)")
        if s.mass_g is None:
            yield Problem(sp + ("mass_g",), "is missing; give the mass of one unit (0 if it stays out of the rig)")
        if s.waste_percent:
            yield Problem(sp + ("waste_percent",), "only applies to a computed quantity (quantity_from)")
        return
    if s.quantity is not None:
        yield Problem(sp + ("quantity",), f"is {s.quantity:g}, but quantity_from: {s.quantity_from} computes it; "
                                          "remove one of them")
    if s.quantity_from == "cable_routes":
        if s.mass_g is None:
            yield Problem(sp + ("mass_g",), "is missing; give the mass of one cable")
        if s.unit != "pcs":
            yield Problem(sp + ("unit",), f"is {s.unit}; cables counted from the routes are bought by the piece (pcs)")
        if s.waste_percent:
            yield Problem(sp + ("waste_percent",), "does not apply to cables counted from the routes")
        return
    if s.mass_g is not None:
        yield Problem(sp + ("mass_g",), "is counted on the printed parts' lines (CAD volume x density); remove it")
    if s.unit not in ("g", "kg"):
        yield Problem(sp + ("unit",), f"is {s.unit}; filament computed from printed_parts is bought by g or kg")
    material = rig.desc.printing.printer.material
    if material.lower() not in (s.part_number + " " + s.description).lower():
        yield Problem(sp + ("part_number",), f"is {s.part_number!r}, but the rig prints in {material} "
                                             "(printing.printer.material)")


def _vendor(e: CatalogueEntry, pid: str, rig: Rig) -> str | None:
    """Who the rig description (or the supply) says makes the part."""
    if e.supply is not None:
        return e.supply.vendor
    return rig.desc.parts[pid].vendor if pid in rig.desc.parts else None


def _purchase_rules(cat: Catalogue, rig: Rig) -> Iterator[Problem]:
    """What is to be ordered is a product: a maker part with its evidence, or an entry marked generic."""
    for pid, e in cat.parts.items():
        path = ("parts", pid)
        if e.part is not None and e.generic is not None:
            yield Problem(path + ("generic",), "is given with part; an entry is a maker part or generic, not both")
        if is_search_link(e.link) and e.generic is None:
            yield Problem(path + ("link",), f"is a shop search ({e.link}), not a product page; link the maker "
                                            "part's product page, or mark the entry generic: <why no MPN was "
                                            "verified>")
        vendor = _vendor(e, pid, rig)
        if (e.made is None and e.included_with is None and vendor is not None and vendor.lower() == "generic"
                and e.part is None and e.generic is None):
            yield Problem(path, "has vendor generic and no maker part; add part: {maker, mpn, source, verified} "
                                "or generic: <why no MPN was verified>")
        if e.part is not None:
            yield from _evidence_rules(e.part, path + ("part",))
            yield from _identity_rules(e.part, pid, rig, path + ("part",))
            if e.part.ratings is not None and pid in rig.desc.parts:
                yield from _rating_rules(e.part, pid, rig, path + ("part", "ratings"))


def _identity_rules(part: MakerPart, pid: str, rig: Rig, path: tuple) -> Iterator[Problem]:
    """Maker and MPN said once: a rig part's are its vendor and part_number in config/rig.yaml; a supply
    or a candidate (a part the rig does not describe yet) names its own."""
    mine = rig.desc.parts.get(pid)
    if mine is None or part.candidate is not None:
        for key in ("maker", "mpn"):
            if not (getattr(part, key) or "").strip():
                yield Problem(path + (key,), "is missing; " + ("a candidate the rig description does not hold yet"
                                                              if mine is not None else "a part not in the rig "
                                                              "description") + " names its maker and MPN")
        if mine is not None and (part.maker, part.mpn) == (mine.vendor, mine.part_number):
            yield Problem(path + ("candidate",), f"is given, but config/rig.yaml parts.{pid} already is "
                                                 f"{mine.vendor} {mine.part_number}; remove candidate, maker and mpn")
        return
    for key, rig_key, have in (("maker", "vendor", mine.vendor), ("mpn", "part_number", mine.part_number)):
        if getattr(part, key) is not None:
            yield Problem(path + (key,), f"is {getattr(part, key)!r}; the rig description holds it "
                                         f"(config/rig.yaml parts.{pid}.{rig_key}: {have!r}): remove it here")
    if mine.vendor.lower() == "generic":
        yield Problem(path, f"names no candidate, but config/rig.yaml parts.{pid} is generic: put the maker and "
                            f"MPN in parts.{pid}.vendor and part_number, or mark this part a candidate")


def _evidence_rules(part: MakerPart, path: tuple) -> Iterator[Problem]:
    """A verified MPN names the page it was read on; an unverified one says so; ratings need a page."""
    if part.verified and not part.source.startswith(("https://", "http://")):
        yield Problem(path + ("source",), f"is {part.source!r}; verified: true needs the address of the page the "
                                          "MPN was read on")
    if not part.verified and not part.source.lower().startswith(UNVERIFIED):
        yield Problem(path + ("source",), f"is {part.source!r}; an MPN not verified here needs a source starting "
                                          f"{UNVERIFIED!r}, then what the MPN rests on")
    if not part.verified and part.ratings is not None:
        yield Problem(path + ("ratings",), "are given for an MPN not verified here; ratings are copied from the "
                                           "page in source (verified: true), or left out")


def _rating_rules(part: MakerPart, pid: str, rig: Rig, path: tuple) -> Iterator[Problem]:
    """The part's datasheet ratings against what config/rig.yaml assumes of it (cad/electrical.py's checks
    use those) and against the battery it hangs on."""
    from cad.bought.base import part_of_kind
    r, mine = part.ratings, rig.part(pid)
    mpn = part.mpn or mine.part_number
    bat_id = part_of_kind(rig, "battery")
    bat = rig.part(bat_id)
    low_v = bat.cutoff_v.value if bat.cutoff_v is not None else bat.output_v.min
    if r.dc_current_a is not None and mine.rating_a is not None and r.dc_current_a < mine.rating_a.value:
        yield Problem(path + ("dc_current_a",), f"{mpn} is rated {r.dc_current_a:g} A; config/rig.yaml assumes "
                                                f"{mine.rating_a.value:g} A (parts.{pid}.rating_a, checked by "
                                                "cad/electrical.py)")
    if r.dc_voltage_v is not None:
        need, why = max((bat.output_v.max, f"the battery's full {bat.output_v.max:g} V (parts.{bat_id}.output_v.max)"),
                        (mine.rating_dc_v.value if mine.rating_dc_v else 0.0, f"parts.{pid}.rating_dc_v"))
        if r.dc_voltage_v < need:
            yield Problem(path + ("dc_voltage_v",), f"{mpn} is rated to {r.dc_voltage_v:g} V DC; it must "
                                                    f"stand {need:g} V ({why})")
    if r.input_v is not None and not r.input_v.min <= low_v <= bat.output_v.max <= r.input_v.max:
        yield Problem(path + ("input_v",), f"{mpn} works from {r.input_v.min:g} to {r.input_v.max:g} V; the "
                                           f"battery gives {low_v:g} V (cut-off) to {bat.output_v.max:g} V "
                                           f"(parts.{bat_id})")
    for key, want in (("output_v", mine.output_v), ("supply_v", mine.supply_v)):
        got = getattr(r, key)
        if got is not None and want is not None and not got.min <= want.min <= want.max <= got.max:
            yield Problem(path + (key,), f"{mpn} is rated {got.min:g}-{got.max:g} V; config/rig.yaml assumes "
                                         f"{want.min:g}-{want.max:g} V (parts.{pid}.{key})")
