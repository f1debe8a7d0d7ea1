"""The bill of materials: the CAD assembly walked node by node, joined with the catalogue.

Nothing here is typed in by hand: the quantity of every placed part is the number of assembly nodes
carrying its id (screws per thread and length, from the joints' geometry), its mass comes from the rig
(bought parts) or from the CAD volume x density (printed and machined parts), the filament to buy is the
printed parts' mass plus the catalogue's waste allowance, and whole packs are bought per line.

:func:`build_bom` raises :class:`BomError` (one line per problem, naming the catalogue file and entry)
when the assembly places a part the catalogue does not list, or the catalogue lists a part that is used
nowhere.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from cad.bought.fasteners import Screw, Standoff
from platform_tools.rig.problems import InputProblems

from .catalogue import LoadedCatalogue
from .catalogue_schema import Category, CatalogueEntry

#: order of the groups in every output
CATEGORY_ORDER = [c.value for c in (Category.SENSORS, Category.COMPUTE, Category.POWER, Category.THERMAL,
                                    Category.ELECTRONICS, Category.CABLES, Category.FASTENERS, Category.PRINTED,
                                    Category.CONSUMABLES)]


class BomError(InputProblems):
    """The assembly and the catalogue do not join: one line per problem."""


@dataclass
class Line:
    key: str                   # catalogue id, or a screw's bom_key ("m3_screw:M3x8": one line per length)
    entry_id: str              # catalogue id
    category: str
    name: str
    vendor: str
    part_number: str
    supplier: str
    link: str
    quantity: float
    unit: str
    pack_size: int
    packs: int
    pack_price: float          # base currency
    price_note: str            # original price, confidence, date checked
    cost: float                # packs x pack price: what you pay
    unit_mass_g: float | None
    mass_g: float              # what it adds to the rig
    mass_source: str
    source: str                # "CAD assembly", "catalogue", "printed volumes"
    nodes: list[str] = field(default_factory=list)
    thread: str | None = None
    length_mm: float | None = None
    estimate: bool = False

    @property
    def quantity_text(self) -> str:
        q = self.quantity
        return f"{q:g}" if self.unit == "pcs" else f"{q:.0f} {self.unit}" if self.unit == "g" else f"{q:g} {self.unit}"


@dataclass
class PrintedPart:
    part_id: str
    category: str              # printed | machined
    quantity: int
    material: str
    volume_mm3: float          # one part
    mass_g: float              # one part
    filament_m: float | None   # one part (printed only)
    orientation_rpy_deg: tuple[float, float, float] | None
    note: str
    size_on_bed_mm: tuple[float, float, float] | None
    fits_bed: bool | None
    nodes: list[str]

    @property
    def total_mass_g(self) -> float:
        return self.mass_g * self.quantity


@dataclass
class Bom:
    rig_name: str
    rig_hash: str
    overrides: tuple[str, ...]
    currency: str
    catalogue_path: str
    rates_checked: str
    lines: list[Line]
    made: list[PrintedPart]
    printer: dict
    cables: list[dict] = field(default_factory=list)   # per cable route: cad.cables.cable_lengths

    def by_category(self) -> list[tuple[str, list[Line], float, float]]:
        out = []
        for cat in CATEGORY_ORDER:
            ls = [ln for ln in self.lines if ln.category == cat]
            if ls:
                out.append((cat, ls, sum(ln.cost for ln in ls), sum(ln.mass_g for ln in ls)))
        return out

    @property
    def total_cost(self) -> float:
        return sum(ln.cost for ln in self.lines)

    @property
    def total_mass_g(self) -> float:
        return sum(ln.mass_g for ln in self.lines)

    @property
    def estimated_cost(self) -> float:
        return sum(ln.cost for ln in self.lines if ln.estimate)

    def line(self, key: str) -> Line:
        for ln in self.lines:
            if ln.key == key:
                return ln
        raise KeyError(key)

    def line_of_node(self) -> dict[str, str]:
        return {n: ln.key for ln in self.lines for n in ln.nodes}

    def to_data(self) -> dict:
        return dict(rig=self.rig_name, rig_hash=self.rig_hash, overrides=list(self.overrides), currency=self.currency,
                    total_cost=round(self.total_cost, 2), total_mass_g=round(self.total_mass_g, 1),
                    lines=[{k: v for k, v in vars(ln).items()} for ln in self.lines],
                    made_parts=[vars(p) for p in self.made])


def build_bom(asm, cat: LoadedCatalogue) -> Bom:
    """The bill of ``asm`` (a :class:`cad.assembly.Assembly`) joined with the catalogue ``cat``.
    Raises :class:`BomError` when the two do not join."""
    from cad.cables import cable_lengths
    buckets, made_nodes = _walk(asm)
    cables = cable_lengths(asm)
    problems = _join_problems(cat, buckets, made_nodes) + _cable_problems(cat, cables)
    if problems:
        raise BomError(problems)
    rig = asm.rig
    printer = rig.desc.printing.printer
    made = _made_parts(asm, made_nodes)
    filament = _filament_ids(cat)
    lines = [_placed_line(rig, cat, key, nodes, made) for key, nodes in buckets.items()]
    lines += [_printed_line(mp, filament[0], printer.density_g_cm3) for mp in made if mp.category == "printed"]
    printed_mass = sum(mp.total_mass_g for mp in made if mp.category == "printed")
    lines += [_supply_line(cat, pid, e, printed_mass, cables) for pid, e in cat.entries.items() if not e.in_cad]
    order = {c: i for i, c in enumerate(CATEGORY_ORDER)}
    # stable: assembly order within a category; fasteners by part, then thread and length
    lines.sort(key=lambda ln: (order.get(ln.category, 99), ln.entry_id if ln.category == "fasteners" else "",
                               ln.length_mm or 0.0))
    return Bom(rig_name=rig.desc.name, rig_hash=rig.hash, overrides=tuple(rig.overrides),
               currency=cat.catalogue.base_currency, catalogue_path=str(cat.path),
               rates_checked=cat.catalogue.rates_checked, lines=lines, made=made, printer=_printer_summary(printer),
               cables=cables)


def _walk(asm) -> tuple[dict[str, list], dict[str, list]]:
    """The assembly's nodes, in assembly order: one bucket per BOM line (bought parts by id, fasteners
    by id, thread and length, machined parts by id), and the printed and machined nodes by part id."""
    buckets: dict[str, list] = {}
    made_nodes: dict[str, list] = {}
    for n in asm.nodes:
        if n.category == "printed":
            made_nodes.setdefault(n.part_id, []).append(n)
            continue
        key = n.spec.bom_key if n.category == "fastener" else n.part_id   # a Screw per thread and length
        buckets.setdefault(key, []).append(n)
        if n.category == "machined":
            made_nodes.setdefault(n.part_id, []).append(n)
    return buckets, made_nodes


def _filament_ids(cat: LoadedCatalogue) -> list[str]:
    """The catalogue entries that supply the printed parts' material."""
    return [pid for pid, e in cat.entries.items() if e.supply is not None and e.supply.quantity_from == "printed_parts"]


def _join_problems(cat: LoadedCatalogue, buckets: dict[str, list], made_nodes: dict[str, list]) -> list[str]:
    """Every way the assembly and the catalogue fail to join, one line each naming file and entry."""
    entries, file = cat.entries, cat.path
    problems: list[str] = []
    by_part: dict[str, list] = {}
    for nodes in buckets.values():
        by_part.setdefault(nodes[0].part_id, []).extend(nodes)
    for pid, nodes in by_part.items():
        if pid not in entries:
            names = ", ".join(x.name for x in nodes[:4]) + (" ..." if len(nodes) > 4 else "")
            what = "a machined part: add it with made: machined and a per-piece price" \
                if nodes[0].category == "machined" else "add its supplier, link and price"
            problems.append(f"{file}: parts.{pid}: missing: the CAD assembly places {pid} ({names}); {what}")
    printed_ids = [pid for pid, ns in made_nodes.items() if ns[0].category == "printed"]
    if printed_ids and not _filament_ids(cat):
        problems.append(f"{file}: parts: no entry supplies the printed parts ({', '.join(printed_ids)}); add the "
                        "filament with in_cad: false and supply.quantity_from: printed_parts")
    for pid, e in entries.items():
        if not e.in_cad:
            continue
        if pid in made_nodes and made_nodes[pid][0].category == "printed":
            problems.append(f"{cat.where(pid)}: parts.{pid}: is a printed part; it is bought as filament "
                            f"(the entry with quantity_from: printed_parts); remove this entry")
        elif pid not in by_part:
            problems.append(f"{cat.where(pid)}: parts.{pid}: used nowhere: the CAD assembly places no {pid} with "
                            "these rig values; remove the entry, or declare it in_cad: false with a supply if the "
                            "rig needs it anyway")
        elif e.made and buckets[pid][0].category != "machined":
            problems.append(f"{cat.where(pid)}: parts.{pid}: made: {e.made}, but the CAD assembly places {pid} as a "
                            f"{buckets[pid][0].category} part; remove made")
        elif not e.made and buckets.get(pid, [None])[0] is not None and buckets[pid][0].category == "machined":
            problems.append(f"{cat.where(pid)}: parts.{pid}: is machined from the CAD model; add made: machined")
    return problems


def _cable_problems(cat: LoadedCatalogue, cables: list[dict]) -> list[str]:
    """Every cable route bought as a catalogue entry that is not there, and every entry counted from the
    routes that no route uses."""
    out = []
    for c in cables:
        if c["catalogue"] is not None and c["catalogue"] not in cat.entries:
            out.append(f"{cat.path}: parts.{c['catalogue']}: missing: cable route {c['route']} (cad/cables.py) is "
                       "bought as it")
        if c["bought_mm"] is None:
            out.append(f"cad/bought/cables.yaml: kinds.{c['kind']}: no stock length holds cable route {c['route']} "
                       f"({c['route_mm']:g} mm + {c['slack_mm']:g} mm slack)")
    used = {c["catalogue"] for c in cables}
    for pid, e in cat.entries.items():
        if e.supply is not None and e.supply.quantity_from == "cable_routes" and pid not in used:
            out.append(f"{cat.where(pid)}: parts.{pid}: quantity_from: cable_routes, but no cable route of the CAD "
                       "model is bought as it")
    return out


def _made_parts(asm, made_nodes: dict[str, list]) -> list[PrintedPart]:
    """Printed and machined parts: volume (CAD, mm^3), mass (g), filament length (m), bed fit."""
    from cad.assembly import PRINT_SETUPS
    from cad.parts.common import on_bed

    desc = asm.rig.desc
    printer, hs = desc.printing.printer, desc.enclosure.heat_sink
    fil_area = math.pi / 4 * printer.filament_diameter_mm ** 2
    made: list[PrintedPart] = []
    for pid, nodes in made_nodes.items():
        n = nodes[0]
        vol = n.local_shape(asm.cache).Volume()
        names = [x.name for x in nodes]
        if n.category != "printed":
            made.append(PrintedPart(part_id=pid, category="machined", quantity=len(nodes), material=hs.material,
                                    volume_mm3=vol, mass_g=vol / 1000 * hs.density_g_cm3, filament_m=None,
                                    orientation_rpy_deg=None, note="machined from the exported STEP",
                                    size_on_bed_mm=None, fits_bed=None, nodes=names))
            continue
        setup = PRINT_SETUPS.get(pid)
        size, fits = None, None
        if setup is not None:
            placed, _ = on_bed(n.local_shape(asm.cache), setup, printer.bed_mm)
            bb = placed.BoundingBox()
            size = (round(bb.xlen, 1), round(bb.ylen, 1), round(bb.zlen, 1))
            fits = bool(np.all(np.array(size) <= np.array(printer.bed_mm) + 1e-6))
        made.append(PrintedPart(part_id=pid, category="printed", quantity=len(nodes), material=printer.material,
                                volume_mm3=vol, mass_g=vol / 1000 * printer.density_g_cm3,
                                filament_m=vol / fil_area / 1000, orientation_rpy_deg=tuple(setup.rpy_deg) if setup else None,
                                note=setup.why if setup else "", size_on_bed_mm=size, fits_bed=fits, nodes=names))
    return made


def _price(cat: LoadedCatalogue, e: CatalogueEntry) -> tuple[float, str]:
    """One pack's price in the base currency, and the note that says where it comes from."""
    if e.price is None:
        return 0.0, f"fitted to {e.included_with}: priced on its line"
    amount = e.price.amount
    if e.price.currency != cat.catalogue.base_currency:
        amount *= cat.catalogue.exchange_rates[e.price.currency]
    note = f"{e.price.amount:g} {e.price.currency}" + (f" per {e.pack_size}" if e.pack_size > 1 else "") + \
           f", {e.price.confidence.value} {e.price.checked}"
    return amount, note


def _placed_line(rig, cat: LoadedCatalogue, key: str, nodes: list, made: list[PrintedPart]) -> Line:
    """The line of a bucket of placed nodes: a bought part, a fastener size or a machined part."""
    n = nodes[0]
    e = cat.entries[n.part_id]
    pack_price, note = _price(cat, e)
    qty = len(nodes)
    packs = math.ceil(qty / e.pack_size)
    fastener = n.spec if n.category == "fastener" else None
    thread = fastener.thread if fastener is not None else None
    length = fastener.length_mm if isinstance(fastener, (Screw, Standoff)) else None
    fmt = dict(thread=thread or "", length_mm=f"{length:g}" if length is not None else "")
    if n.category == "machined":
        mp = next(p for p in made if p.part_id == n.part_id)
        density = rig.desc.enclosure.heat_sink.density_g_cm3
        name = f"{mp.material} {n.part_id.replace('_', ' ')}, machined to the CAD model"
        vendor, number = e.supplier, f"{n.part_id}.step"
        unit_mass, mass_src = mp.mass_g, f"CAD volume {mp.volume_mm3 / 1000:.1f} cm3 x {density:g} g/cm3"
    else:
        part = rig.part(n.part_id)
        name = part.description
        if length is not None:
            name = f"{thread} x {length:g} mm, {part.part_number}"
        vendor, number = part.vendor, part.part_number
        unit_mass, mass_src = part.mass_g.value, "rig"
    return Line(key=key, entry_id=n.part_id, category=e.category.value, name=name, vendor=vendor, part_number=number,
                supplier=e.supplier, link=e.link.format(**fmt), quantity=qty, unit="pcs", pack_size=e.pack_size,
                packs=packs, pack_price=pack_price, price_note=note, cost=packs * pack_price, unit_mass_g=unit_mass,
                mass_g=unit_mass * qty, mass_source=mass_src, source="CAD assembly", nodes=[x.name for x in nodes],
                thread=thread, length_mm=length, estimate=e.price is not None and e.price.confidence.value == "estimate")


def _printed_line(mp: PrintedPart, filament_id: str, density_g_cm3: float) -> Line:
    """A printed part's line: its mass counts here, its cost is in the filament's line."""
    return Line(key=mp.part_id, entry_id=filament_id, category="printed",
                name=f"{mp.part_id.replace('_', ' ')} (printed, {mp.material})", vendor="printed",
                part_number=f"{mp.part_id}.stl", supplier="print it yourself", link="printing.html",
                quantity=mp.quantity, unit="pcs", pack_size=1, packs=0, pack_price=0.0,
                price_note=f"material in {filament_id}", cost=0.0, unit_mass_g=mp.mass_g, mass_g=mp.total_mass_g,
                mass_source=f"CAD volume x {density_g_cm3:g} g/cm3", source="CAD assembly", nodes=mp.nodes)


def _supply_line(cat: LoadedCatalogue, pid: str, e: CatalogueEntry, printed_mass_g: float,
                 cables: list[dict] = ()) -> Line:
    """A catalogue entry the CAD does not place: the filament (from the printed parts' mass plus waste),
    cables (one per route of the model, at the stock length the longest route needs) or a fixed supply."""
    s = e.supply
    pack_price, note = _price(cat, e)
    number = s.part_number
    if s.quantity_from == "cable_routes":
        mine = [c for c in cables if c["catalogue"] == pid]
        qty_shown = len(mine)
        length = max((c["bought_mm"] or 0.0) for c in mine) if mine else 0.0
        number = s.part_number.format(length_mm=f"{length:g}")
        unit_mass, mass, src, msrc = s.mass_g, s.mass_g * qty_shown, "cable routes", "catalogue"
    elif s.quantity_from == "printed_parts":
        qty = printed_mass_g * (1 + s.waste_percent / 100)
        qty = qty / 1000 if s.unit == "kg" else qty
        unit_mass, mass, src, msrc = None, 0.0, "printed volumes", "counted on the printed parts' lines"
        qty_shown = math.ceil(qty) if s.unit == "g" else round(qty, 3)
    else:
        qty_shown = s.quantity
        unit_mass, mass, src, msrc = s.mass_g, s.mass_g * s.quantity, "catalogue", "catalogue"
    packs = math.ceil(qty_shown / e.pack_size - 1e-9)
    return Line(key=pid, entry_id=pid, category=e.category.value, name=s.description, vendor=s.vendor,
                part_number=number, supplier=e.supplier, link=e.link, quantity=qty_shown, unit=s.unit,
                pack_size=e.pack_size, packs=packs, pack_price=pack_price, price_note=note, cost=packs * pack_price,
                unit_mass_g=unit_mass, mass_g=mass, mass_source=msrc, source=src, nodes=[],
                estimate=e.price is not None and e.price.confidence.value == "estimate")


def _printer_summary(printer) -> dict:
    """The printer settings the printing page shows."""
    return dict(name=printer.name, material=printer.material, nozzle_mm=printer.nozzle_mm,
                layer_mm=printer.layer_mm, bed_mm=tuple(printer.bed_mm),
                density_g_cm3=printer.density_g_cm3, filament_diameter_mm=printer.filament_diameter_mm,
                min_wall_mm=printer.min_wall_nozzles * printer.nozzle_mm,
                max_overhang_deg=printer.max_overhang_deg, max_bridge_mm=printer.max_bridge_mm)
