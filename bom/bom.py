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
    key: str                   # catalogue id, or "m3_screw:M3x8" for a fastener length
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


def fastener_key(part_id: str, props: dict) -> str:
    """The BOM line of a fastener node: screws per thread and length (as cad.assembly counts them)."""
    if "length_mm" in props:
        return f"{part_id}:{props['thread']}x{props['length_mm']:g}"
    return part_id


def build_bom(asm, cat: LoadedCatalogue) -> Bom:
    from cad.assembly import PRINT_SETUPS
    from cad.parts.common import on_bed

    rig = asm.rig
    desc = rig.desc
    entries = cat.entries
    file = cat.path
    base = cat.catalogue.base_currency
    problems: list[str] = []

    # ---- walk the assembly: one bucket per BOM line, in assembly order
    buckets: dict[str, list] = {}
    made_nodes: dict[str, list] = {}
    for n in asm.nodes:
        if n.category == "printed":
            made_nodes.setdefault(n.part_id, []).append(n)
            continue
        key = fastener_key(n.part_id, n.props) if n.category == "fastener" else n.part_id
        buckets.setdefault(key, []).append(n)
        if n.category == "machined":
            made_nodes.setdefault(n.part_id, []).append(n)

    by_part: dict[str, list] = {}
    for nodes in buckets.values():
        by_part.setdefault(nodes[0].part_id, []).extend(nodes)
    placed_ids = set(by_part)
    for pid, nodes in by_part.items():
        if pid not in entries:
            names = ", ".join(x.name for x in nodes[:4]) + (" ..." if len(nodes) > 4 else "")
            what = "a machined part: add it with made: machined and a per-piece price" \
                if nodes[0].category == "machined" else "add its supplier, link and price"
            problems.append(f"{file}: parts.{pid}: missing: the CAD assembly places {pid} ({names}); {what}")
    filament = [pid for pid, e in entries.items() if e.supply is not None and e.supply.quantity_from == "printed_parts"]
    printed_ids = [pid for pid, ns in made_nodes.items() if ns[0].category == "printed"]
    if printed_ids and not filament:
        problems.append(f"{file}: parts: no entry supplies the printed parts ({', '.join(printed_ids)}); add the "
                        "filament with in_cad: false and supply.quantity_from: printed_parts")
    for pid, e in entries.items():
        if not e.in_cad:
            continue
        if pid in made_nodes and made_nodes[pid][0].category == "printed":
            problems.append(f"{cat.where(pid)}: parts.{pid}: is a printed part; it is bought as filament "
                            f"(the entry with quantity_from: printed_parts); remove this entry")
        elif pid not in placed_ids:
            problems.append(f"{cat.where(pid)}: parts.{pid}: used nowhere: the CAD assembly places no {pid} with "
                            "these rig values; remove the entry, or declare it in_cad: false with a supply if the "
                            "rig needs it anyway")
        elif e.made and buckets[pid][0].category != "machined":
            problems.append(f"{cat.where(pid)}: parts.{pid}: made: {e.made}, but the CAD assembly places {pid} as a "
                            f"{buckets[pid][0].category} part; remove made")
        elif not e.made and buckets.get(pid, [None])[0] is not None and buckets[pid][0].category == "machined":
            problems.append(f"{cat.where(pid)}: parts.{pid}: is machined from the CAD model; add made: machined")
    if problems:
        raise BomError(problems)

    # ---- made parts (printed and machined): volume, mass, filament length, bed fit
    printer = desc.printing.printer
    hs = desc.enclosure.heat_sink
    fil_area = math.pi / 4 * printer.filament_diameter_mm ** 2
    made: list[PrintedPart] = []
    for pid, nodes in made_nodes.items():
        n = nodes[0]
        vol = n.local_shape(asm.cache).Volume()
        if n.category == "printed":
            mass = vol / 1000 * printer.density_g_cm3
            setup = PRINT_SETUPS.get(pid)
            size, fits = None, None
            if setup is not None:
                placed, _ = on_bed(n.local_shape(asm.cache), setup, printer.bed_mm)
                bb = placed.BoundingBox()
                size = (round(bb.xlen, 1), round(bb.ylen, 1), round(bb.zlen, 1))
                fits = bool(np.all(np.array(size) <= np.array(printer.bed_mm) + 1e-6))
            made.append(PrintedPart(pid, "printed", len(nodes), printer.material, vol, mass, vol / fil_area / 1000,
                                    tuple(setup.rpy_deg) if setup else None, setup.why if setup else "",
                                    size, fits, [x.name for x in nodes]))
        else:
            made.append(PrintedPart(pid, "machined", len(nodes), hs.material, vol, vol / 1000 * hs.density_g_cm3,
                                    None, None, "machined from the exported STEP", None, None,
                                    [x.name for x in nodes]))

    # ---- lines
    def price(e: CatalogueEntry) -> tuple[float, str]:
        amount = e.price.amount
        if e.price.currency != base:
            amount *= cat.catalogue.exchange_rates[e.price.currency]
        note = f"{e.price.amount:g} {e.price.currency}" + (f" per {e.pack_size}" if e.pack_size > 1 else "") + \
               f", {e.price.confidence.value} {e.price.checked}"
        return amount, note

    lines: list[Line] = []
    for key, nodes in buckets.items():
        n = nodes[0]
        e = entries[n.part_id]
        pack_price, note = price(e)
        qty = len(nodes)
        packs = math.ceil(qty / e.pack_size)
        thread, length = n.props.get("thread"), n.props.get("length_mm")
        fmt = dict(thread=thread or "", length_mm=f"{length:g}" if length is not None else "")
        if n.category == "machined":
            mp = next(p for p in made if p.part_id == n.part_id)
            name = f"{mp.material} {n.part_id.replace('_', ' ')}, machined to the CAD model"
            vendor, number = e.supplier, f"{n.part_id}.step"
            unit_mass, mass_src = mp.mass_g, f"CAD volume {mp.volume_mm3 / 1000:.1f} cm3 x {hs.density_g_cm3:g} g/cm3"
        else:
            part = rig.part(n.part_id)
            name = part.description
            if length is not None:
                name = f"{thread} x {length:g} mm, {part.part_number}"
            vendor, number = part.vendor, part.part_number
            unit_mass, mass_src = part.mass_g.value, "rig"
        lines.append(Line(key, n.part_id, e.category.value, name, vendor, number, e.supplier, e.link.format(**fmt),
                          qty, "pcs", e.pack_size, packs, pack_price, note, packs * pack_price, unit_mass,
                          unit_mass * qty, mass_src, "CAD assembly", [x.name for x in nodes], thread, length,
                          e.price.confidence.value == "estimate"))
    # printed parts: mass on their own line, cost in the filament
    for mp in made:
        if mp.category != "printed":
            continue
        lines.append(Line(mp.part_id, filament[0], "printed", f"{mp.part_id.replace('_', ' ')} (printed, {mp.material})",
                          "printed", f"{mp.part_id}.stl", "print it yourself", "printing.html", mp.quantity, "pcs",
                          1, 0, 0.0, f"material in {filament[0]}", 0.0, mp.mass_g, mp.total_mass_g,
                          f"CAD volume x {printer.density_g_cm3:g} g/cm3", "CAD assembly", mp.nodes))
    printed_mass = sum(mp.total_mass_g for mp in made if mp.category == "printed")
    for pid, e in entries.items():
        if e.in_cad:
            continue
        s = e.supply
        pack_price, note = price(e)
        if s.quantity_from == "printed_parts":
            qty = printed_mass * (1 + s.waste_percent / 100)
            qty = qty / 1000 if s.unit == "kg" else qty
            unit_mass, mass, src, msrc = None, 0.0, "printed volumes", "counted on the printed parts' lines"
            qty_shown = math.ceil(qty) if s.unit == "g" else round(qty, 3)
        else:
            qty_shown = s.quantity
            unit_mass, mass, src, msrc = s.mass_g, s.mass_g * s.quantity, "catalogue", "catalogue"
        packs = math.ceil(qty_shown / e.pack_size - 1e-9)
        lines.append(Line(pid, pid, e.category.value, s.description, s.vendor, s.part_number, e.supplier, e.link,
                          qty_shown, s.unit, e.pack_size, packs, pack_price, note, packs * pack_price, unit_mass,
                          mass, msrc, src, [], estimate=e.price.confidence.value == "estimate"))
    order = {c: i for i, c in enumerate(CATEGORY_ORDER)}
    # stable: assembly order within a category; fasteners by part, then thread and length
    lines.sort(key=lambda ln: (order.get(ln.category, 99), ln.entry_id if ln.category == "fasteners" else "",
                               ln.length_mm or 0.0))
    return Bom(desc.name, rig.hash, tuple(rig.overrides), base, str(file), cat.catalogue.rates_checked, lines, made,
               dict(name=printer.name, material=printer.material, nozzle_mm=printer.nozzle_mm,
                    layer_mm=printer.layer_mm, bed_mm=tuple(printer.bed_mm),
                    density_g_cm3=printer.density_g_cm3, filament_diameter_mm=printer.filament_diameter_mm,
                    min_wall_mm=printer.min_wall_nozzles * printer.nozzle_mm,
                    max_overhang_deg=printer.max_overhang_deg, max_bridge_mm=printer.max_bridge_mm))
