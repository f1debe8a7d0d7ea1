"""The catalogue of bought parts (bom/parts.yaml): what to buy, where, and for how much.

The catalogue holds only purchasing facts. What a part *is* (vendor, part number, mass, size) lives in
the rig description for every part the CAD model places; the catalogue names those parts by their
rig id and adds the link and the price. Parts the CAD model does not place (cables, the data drive,
filament, thermal paste) are declared here in full, with `in_cad: false` and a quantity per rig.

Three kinds of entry:

- a rig part (its id is a key of ``parts:`` in config/rig.yaml): link and price only; the quantity is
  counted from the CAD assembly, the mass comes from the rig;
- a made part the CAD model places but no shop sells off the shelf (``made: machined``, the copper
  heat sink): the price is a job shop's per-piece price for machining it from the CAD model (material
  included); the quantity is counted from the assembly, the material from the rig, the mass from the CAD
  volume x the rig's density;
- a supply (``in_cad: false``): declared in full under ``supply``, with a quantity per rig, or
  ``quantity_from: printed_parts`` for the filament, whose quantity the BOM computes from the printed
  volumes (plus ``waste_percent`` for purge, brims and failed prints).

``price.amount`` is the price of one pack of ``pack_size`` units; the BOM buys whole packs.

What to order: an entry names either the manufacturer part to buy (``part``: the page the MPN was read
on, and the ratings copied from that page) or says why none could be verified (``generic``); an entry
whose vendor is "generic" must do one or the other, and only a generic entry may link to a shop search
(catalogue._purchase_rules). The maker and MPN of a rig part are said once, in config/rig.yaml
(``parts.<id>.vendor`` and ``part_number``): its ``part`` block holds only the evidence. A supply, or a
``candidate`` the CAD model cannot hold yet (the rig then still describes its estimate), names its own.
"""
from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import Annotated, Literal, Mapping, Optional

from platform_tools.rig.schema import VoltageRange
from platform_tools.rig.typed import Ge, Gt, Unit

#: ISO 4217 codes the catalogue accepts; a price in another currency is refused by name
Currency = Literal["USD", "EUR", "GBP", "CHF", "CAD", "AUD", "JPY", "CNY"]
IsoDate = Annotated[str, "YYYY-MM-DD"]
Amp = Annotated[float, Unit("A"), Gt(0)]
Volt = Annotated[float, Unit("V"), Gt(0)]


class Category(enum.Enum):
    SENSORS = "sensors"
    COMPUTE = "compute"
    POWER = "power"
    THERMAL = "thermal"
    FASTENERS = "fasteners"
    CABLES = "cables"
    ELECTRONICS = "electronics"
    PRINTED = "printed"
    CONSUMABLES = "consumables"


class PriceConfidence(enum.Enum):
    QUOTED = "quoted"        # read from the supplier's page on price_checked
    ESTIMATE = "estimate"    # a typical price; check before ordering


@dataclass(frozen=True)
class Price:
    amount: Annotated[float, Gt(0)]
    currency: Currency
    checked: IsoDate
    confidence: PriceConfidence

    def __post_init__(self) -> None:
        import datetime
        try:
            datetime.date.fromisoformat(self.checked)
        except ValueError:
            raise ValueError(f"checked: {self.checked!r} is not a date; expected YYYY-MM-DD") from None


@dataclass(frozen=True)
class Supply:
    """A part not placed by the CAD model: everything about it is declared here."""
    vendor: str
    part_number: str
    description: str
    unit: Literal["pcs", "m", "g", "kg", "ml"]
    why: str  # what it is for, since no geometry shows it
    #: mass of one unit (one piece, one metre ...); omitted for a quantity_from supply (its mass is
    #: the printed parts' own, counted on their lines)
    mass_g: Optional[Annotated[float, Ge(0)]] = None
    #: per rig; omitted when quantity_from says where the BOM computes it from
    quantity: Optional[Annotated[float, Gt(0)]] = None
    #: printed_parts: the sum of the printed parts' masses from their CAD volumes (unit g or kg);
    #: cable_routes: one piece per cable route of the CAD model bought as this entry (cad/cables.py), its
    #: stock length written into the part number's ``{length_mm}``
    quantity_from: Optional[Literal["printed_parts", "cable_routes"]] = None
    #: extra on a computed quantity (purge, brims, a failed print)
    waste_percent: Annotated[float, Ge(0)] = 0.0


@dataclass(frozen=True)
class Ratings:
    """A chosen part's ratings, every one copied from its ``MakerPart.source`` (the page they were read
    on). cad/electrical.py sizes the rig from the values config/rig.yaml assumes; the catalogue checks
    that the part bought is rated at least that (catalogue._rating_rules)."""
    #: contact or holder current at ``dc_voltage_v`` (switch, fuse holder, cut-off), or a converter's output
    dc_current_a: Optional[Amp] = None
    #: the highest DC voltage ``dc_current_a`` is rated at
    dc_voltage_v: Optional[Volt] = None
    #: the working input range of a part fed from the battery (converter, cut-off)
    input_v: Optional[VoltageRange] = None
    #: a converter's output (a fixed voltage is min = max)
    output_v: Optional[VoltageRange] = None
    #: the supply range of a load (a fan's motor, a button's LED)
    supply_v: Optional[VoltageRange] = None


@dataclass(frozen=True)
class MakerPart:
    """The manufacturer part to order, and the evidence for it."""
    #: the address of the stored page the MPN and ratings were read on (verified: true), or text starting
    #: "not verified here" that says what the MPN rests on instead (verified: false)
    source: str
    #: True only when the MPN and every rating were read on ``source``
    verified: bool
    ratings: Optional[Ratings] = None
    #: what to check before ordering (an option code, a size the CAD model does not have yet)
    note: Optional[str] = None
    #: maker and MPN: for a rig part they are config/rig.yaml's vendor and part_number (given here only
    #: with ``candidate``); a supply names them here
    maker: Optional[str] = None
    mpn: Optional[str] = None
    #: why this part, chosen for the BOM, is not yet the one config/rig.yaml describes (it does not fit the
    #: CAD model): the BOM shows it as a candidate, not as the part to order
    candidate: Optional[str] = None


@dataclass(frozen=True)
class CatalogueEntry:
    category: Category
    supplier: str
    link: str
    #: omitted only for a part that comes fitted to another (``included_with``)
    price: Optional[Price] = None
    #: the catalogue id of the part this one comes fitted to (the lens on its Boson core): no price of its own
    included_with: Optional[str] = None
    #: per-unit price applies to this many units (a bag of 100 screws: pack_size 100)
    pack_size: Annotated[int, Gt(0)] = 1
    #: False for parts the CAD model does not place; they must then declare `supply`
    in_cad: bool = True
    supply: Optional[Supply] = None
    #: a part the CAD model places that is made to order from its geometry (the copper heat sink)
    made: Optional[Literal["machined"]] = None
    #: the manufacturer part to order (maker, MPN, where they were read)
    part: Optional[MakerPart] = None
    #: why no MPN is given (the BOM shows "generic: no MPN verified" and this reason); only such an entry may
    #: link to a shop search, which the BOM then shows as a search, not as a product
    generic: Optional[str] = None


@dataclass(frozen=True)
class Catalogue:
    schema_version: Literal[1]
    base_currency: Currency
    #: units of base currency per unit of each other currency, and when the rate was read
    exchange_rates: Mapping[str, Annotated[float, Gt(0)]]
    rates_checked: IsoDate
    parts: Mapping[str, CatalogueEntry]
