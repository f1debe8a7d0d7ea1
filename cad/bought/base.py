"""What every bought part has in common: its rig part id, its envelope (the space it occupies, read
from the rig description with its source and confidence), a colour, and a builder of its shape in its
own frame. Subclasses add their mounting features and, for cameras, their optical frames.

A bought part is a frozen dataclass of plain numbers, so its ``repr`` is a complete cache key.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from platform_tools.rig import Rig
from platform_tools.rig.schema import Sourced

from cad.geom import Bounds, Vec3

if TYPE_CHECKING:
    import cadquery as cq

Colour = tuple[float, float, float, float]


@dataclass(frozen=True)
class Provenance:
    """One vendor number as the rig description gives it."""
    key: str
    value: float
    source: str
    confidence: str


def part_of_kind(rig: Rig, kind: str) -> str:
    """The id of the rig's (first) part of ``kind`` ("fan", "computer", ...): where a part's id is
    written once, in config/rig.yaml."""
    for pid, part in rig.desc.parts.items():
        if part.kind.value == kind:
            return pid
    raise KeyError(f"the rig has no part of kind {kind}")


def envelope(rig: Rig, part_id: str) -> Vec3:
    e = rig.part(part_id).envelope_mm
    return (e.x.value, e.y.value, e.z.value)


def provenance(rig: Rig, part_id: str) -> list[Provenance]:
    """Every sourced number of a part: envelope, mass and its dims."""
    part = rig.part(part_id)
    rows: list[tuple[str, Sourced]] = [(f"envelope_mm.{a}", getattr(part.envelope_mm, a)) for a in "xyz"]
    rows.append(("mass_g", part.mass_g))
    rows.extend((f"dims.{k}", v) for k, v in part.dims.items())
    return [Provenance(f"parts.{part_id}.{k}", s.value, s.source, s.confidence.value) for k, s in rows]


@dataclass(frozen=True)
class BoughtPart:
    """A bought part as an envelope box centred on its own origin (subclasses move and detail it)."""
    part_id: str
    size: Vec3

    colour: Colour = (0.25, 0.25, 0.28, 1.0)

    def bounds(self) -> Bounds:
        return Bounds.centred((0.0, 0.0, 0.0), self.size)

    def build(self) -> cq.Shape:
        from cad.solids import box
        return box(self.bounds())


def part_colour(kind: str) -> Colour:
    return {
        "camera": (0.12, 0.12, 0.14, 1.0),
        "thermal": (0.35, 0.35, 0.38, 1.0),
        "lens": (0.05, 0.05, 0.05, 1.0),
        "computer": (0.30, 0.45, 0.30, 1.0),
        "card": (0.10, 0.40, 0.15, 1.0),
        "battery": (0.05, 0.55, 0.60, 1.0),
        "adapter": (0.15, 0.15, 0.15, 1.0),
        "fan": (0.10, 0.10, 0.10, 1.0),
        "panel": (0.75, 0.10, 0.10, 1.0),
        "electronics": (0.20, 0.30, 0.60, 1.0),
        "steel": (0.70, 0.70, 0.72, 1.0),
        "brass": (0.80, 0.65, 0.25, 1.0),
    }[kind]
