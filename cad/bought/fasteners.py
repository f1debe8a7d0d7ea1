"""Fasteners, typed in the style of cq_warehouse: a table of thread sizes (``fasteners.yaml`` beside
this file) that answers a thread's diameter, tap drill, screw and insert and the stock lengths; and
the two bought fasteners a joint holds, a :class:`Screw` (socket head, its length picked per joint)
and a heat-set :class:`Insert`, and the hex :class:`Standoff` a board stands on, each with the key its
BOM line counts it by.

Screw frame: origin at the centre of the head's bearing face; the shank runs along -z, the head is
above (z > 0). Insert frame: origin at the centre of its top face (flush with the part's surface);
its body runs along -z. Standoff frame: origin at the centre of its body's bottom face (the face that
bears on the part below); the hex body runs along +z, its male stud along -z.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Mapping, Optional

from platform_tools.rig import Rig
from platform_tools.rig.problems import InputProblems
from platform_tools.rig.typed import Gt
from platform_tools.rig.yamlsource import load_typed

from cad.bought.base import BoughtPart, envelope, part_colour

if TYPE_CHECKING:
    import cadquery as cq

TABLE = Path(__file__).resolve().with_name("fasteners.yaml")


class FastenerTableError(InputProblems):
    """cad/bought/fasteners.yaml is not valid: one line per problem, naming the file and line."""


@dataclass(frozen=True)
class Driver:
    """The tool that drives a thread's screw, as the envelope it sweeps along the screw's axis: a bit
    (``bit_diameter_mm`` across, ``bit_length_mm`` out from the head) then its handle (mm)."""
    bit_diameter_mm: Annotated[float, Gt(0)]
    bit_length_mm: Annotated[float, Gt(0)]
    handle_diameter_mm: Annotated[float, Gt(0)]
    handle_length_mm: Annotated[float, Gt(0)]


@dataclass(frozen=True)
class ThreadSize:
    """One row of the table (mm)."""
    diameter_mm: Annotated[float, Gt(0)]
    screw: str                                   # rig part id of the screw for this thread
    driver: Driver                               # the tool that turns it (its envelope)
    tap_drill_mm: Optional[Annotated[float, Gt(0)]] = None
    insert: Optional[str] = None                 # rig part id of its heat-set insert


@dataclass(frozen=True)
class StandoffSize:
    """The standoffs of one thread: the rig part, the screw into its female end, its stock lengths (mm)."""
    part: str
    screw: str
    stock_lengths_mm: tuple[Annotated[float, Gt(0)], ...]

    def pick_length(self, min_mm: float) -> float:
        """The shortest stock length at least ``min_mm``."""
        for length in sorted(self.stock_lengths_mm):
            if length >= min_mm - 1e-6:
                return float(length)
        raise ValueError(f"no stock {self.part} is {min_mm:g} mm or longer (the longest is "
                         f"{max(self.stock_lengths_mm):g} mm, {TABLE.name})")


@dataclass(frozen=True)
class FastenerTable:
    stock_lengths_mm: tuple[Annotated[float, Gt(0)], ...]
    sizes: Mapping[str, ThreadSize]              # by thread name: "M3", "1/4-20 UNC"
    standoffs: Mapping[str, StandoffSize]        # by thread name

    def standoff(self, thread: str) -> StandoffSize:
        try:
            return self.standoffs[thread]
        except KeyError:
            raise ValueError(f"no standoff for thread {thread!r}; the fastener table ({TABLE.name}) has "
                             f"{', '.join(self.standoffs) or 'none'}") from None

    def size(self, thread: str) -> ThreadSize:
        try:
            return self.sizes[thread]
        except KeyError:
            raise ValueError(f"unknown thread {thread!r}; the fastener table ({TABLE.name}) has "
                             f"{', '.join(self.sizes)}") from None

    def thread_of_insert(self, part_id: str) -> str:
        """The thread of the heat-set insert ``part_id``."""
        for name, s in self.sizes.items():
            if s.insert == part_id:
                return name
        raise ValueError(f"no thread of the fastener table ({TABLE.name}) uses the insert {part_id!r}")

    def pick_length(self, grip_mm: float, min_engage_mm: float, max_engage_mm: float) -> float:
        """The longest stock length whose thread engagement past the clamped parts is within [min, max]."""
        for length in reversed(self.stock_lengths_mm):
            if min_engage_mm - 1e-6 <= length - grip_mm <= max_engage_mm + 1e-6:
                return float(length)
        raise ValueError(f"no stock screw length gives {min_engage_mm:g}-{max_engage_mm:g} mm of thread "
                         f"past a {grip_mm:g} mm grip")


@lru_cache(maxsize=None)
def fastener_table(path: Path = TABLE) -> FastenerTable:
    """The fastener table (read once per process). Raises :class:`FastenerTableError`."""
    return load_typed(path, FastenerTable, FastenerTableError).value


def thread_diameter_mm(thread: str) -> float:
    """Nominal diameter of a thread of the table: 'M3' -> 3.0, 'M2.5' -> 2.5, '1/4-20 UNC' -> 6.35."""
    return fastener_table().size(thread).diameter_mm


def pick_length(grip_mm: float, min_engage_mm: float, max_engage_mm: float) -> float:
    """:meth:`FastenerTable.pick_length` of the project's table."""
    return fastener_table().pick_length(grip_mm, min_engage_mm, max_engage_mm)


@dataclass(frozen=True, kw_only=True)
class Screw(BoughtPart):
    thread: str
    diameter_mm: float
    head_diameter_mm: float
    head_height_mm: float
    length_mm: float

    @classmethod
    def from_rig(cls, rig: Rig, part_id: str, thread: str, length_mm: float) -> "Screw":
        return cls(part_id=part_id, size=envelope(rig, part_id), colour=part_colour("steel"), thread=thread,
                   diameter_mm=thread_diameter_mm(thread), head_diameter_mm=rig.dim(part_id, "head_diameter_mm"),
                   head_height_mm=rig.dim(part_id, "head_height_mm"), length_mm=length_mm)

    @property
    def bom_key(self) -> str:
        """Its BOM line: one per screw part, thread and length ("m3_screw:M3x8")."""
        return f"{self.part_id}:{self.thread}x{self.length_mm:g}"

    def build(self) -> cq.Shape:
        from cad.solids import cylinder
        head = cylinder(self.head_diameter_mm, self.head_height_mm, (0, 0, 0))
        shank = cylinder(self.diameter_mm, self.length_mm, (0, 0, -self.length_mm))
        return head.fuse(shank).clean()


@dataclass(frozen=True, kw_only=True)
class Insert(BoughtPart):
    """A heat-set insert; every size is the rig part's (``parts.<id>``: envelope x = length, y = outer
    diameter; ``dims.hole_diameter_mm``, ``dims.hole_extra_depth_mm``)."""
    outer_diameter_mm: float
    length_mm: float
    bore_mm: float
    hole_diameter_mm: float
    hole_extra_depth_mm: float

    @classmethod
    def from_rig(cls, rig: Rig, part_id: str) -> "Insert":
        x, y, _ = envelope(rig, part_id)
        return cls(part_id=part_id, size=(x, y, y), colour=part_colour("brass"), outer_diameter_mm=y, length_mm=x,
                   bore_mm=thread_diameter_mm(fastener_table().thread_of_insert(part_id)),
                   hole_diameter_mm=rig.dim(part_id, "hole_diameter_mm"),
                   hole_extra_depth_mm=rig.dim(part_id, "hole_extra_depth_mm"))

    @property
    def thread(self) -> str:
        return fastener_table().thread_of_insert(self.part_id)

    @property
    def bom_key(self) -> str:
        """Its BOM line: one per insert part."""
        return self.part_id

    @property
    def hole_depth_mm(self) -> float:
        return self.length_mm + self.hole_extra_depth_mm

    def build(self) -> cq.Shape:
        from cad.solids import tube
        return tube(self.outer_diameter_mm, self.bore_mm, self.length_mm, (0, 0, -self.length_mm))

    def hole(self) -> cq.Shape:
        """The printed hole it is melted into (in the insert's frame)."""
        from cad.solids import cylinder
        return cylinder(self.hole_diameter_mm, self.hole_depth_mm + 0.01, (0, 0, -self.hole_depth_mm))

    def melt_volume_mm3(self) -> float:
        """Plastic the insert displaces: the overlap an interference check must find, no more."""
        return math.pi / 4 * (self.outer_diameter_mm ** 2 - self.hole_diameter_mm ** 2) * self.length_mm


@dataclass(frozen=True, kw_only=True)
class Standoff(BoughtPart):
    """A male-female hex standoff: a hex body ``length_mm`` long, ``across_flats_mm`` across flats, on
    a male stud ``stud_mm`` long; its female thread is ``female_depth_mm`` deep from the top face (the
    body is drawn solid, so a screw's engaged thread is the overlap the interference check expects)."""
    thread: str
    diameter_mm: float
    across_flats_mm: float
    length_mm: float
    stud_mm: float
    female_depth_mm: float

    @classmethod
    def from_rig(cls, rig: Rig, part_id: str, thread: str, length_mm: float) -> "Standoff":
        af = rig.dim(part_id, "across_flats_mm")
        return cls(part_id=part_id, size=(af, af, length_mm), colour=part_colour("brass"), thread=thread,
                   diameter_mm=thread_diameter_mm(thread), across_flats_mm=af, length_mm=length_mm,
                   stud_mm=rig.dim(part_id, "male_thread_length_mm"),
                   female_depth_mm=rig.dim(part_id, "female_thread_depth_mm"))

    @property
    def across_corners_mm(self) -> float:
        return self.across_flats_mm / math.cos(math.radians(30))

    @property
    def bom_key(self) -> str:
        """Its BOM line: one per standoff part, thread and length ("m2p5_standoff:M2.5x15")."""
        return f"{self.part_id}:{self.thread}x{self.length_mm:g}"

    def stud_volume_mm3(self) -> float:
        """The stud's volume: what a tapped hole it is screwed into overlaps."""
        return math.pi / 4 * self.diameter_mm ** 2 * self.stud_mm

    def build(self) -> cq.Shape:
        import cadquery as cq
        from cad.solids import cylinder
        body = cq.Workplane("XY").polygon(6, self.across_corners_mm).extrude(self.length_mm).val()
        stud = cylinder(self.diameter_mm, self.stud_mm, (0, 0, -self.stud_mm))
        return body.fuse(stud).clean()
