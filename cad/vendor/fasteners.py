"""Fasteners: screws (socket head, the length chosen per joint) and heat-set inserts.

Screw frame: origin at the centre of the head's bearing face; the shank runs along -z, the head is
above (z > 0). Insert frame: origin at the centre of its top face (flush with the part's surface);
its body runs along -z. Diameters come from the thread name (M3 -> 3 mm, 1/4-20 -> 6.35 mm).
"""
from __future__ import annotations

import re
from dataclasses import dataclass

import cadquery as cq

from platform_tools.rig import Rig

from ..geom import cylinder, tube
from .base import VendorPart, envelope, part_colour

#: preferred lengths (mm) a screw is picked from, shortest first
STOCK_LENGTHS_MM = (4, 5, 6, 8, 10, 12, 14, 16, 18, 20, 22, 25, 30, 35, 40, 45, 50)


def thread_diameter_mm(thread: str) -> float:
    """Nominal diameter of a thread name: 'M3' -> 3.0, 'M2.5' -> 2.5, '1/4-20 UNC' -> 6.35."""
    m = re.match(r"\s*M(\d+(?:\.\d+)?)", thread)
    if m:
        return float(m.group(1))
    m = re.match(r"\s*(\d+)/(\d+)-\d+", thread)
    if m:
        return 25.4 * int(m.group(1)) / int(m.group(2))
    raise ValueError(f"unknown thread {thread!r}")


def pick_length(grip_mm: float, min_engage_mm: float, max_engage_mm: float) -> float:
    """The longest stock length whose thread engagement past the clamped parts is within [min, max]."""
    for length in reversed(STOCK_LENGTHS_MM):
        if min_engage_mm - 1e-6 <= length - grip_mm <= max_engage_mm + 1e-6:
            return float(length)
    raise ValueError(f"no stock screw length gives {min_engage_mm:g}-{max_engage_mm:g} mm of thread "
                     f"past a {grip_mm:g} mm grip")


@dataclass(frozen=True)
class Screw(VendorPart):
    diameter_mm: float = 3.0
    head_diameter_mm: float = 5.5
    head_height_mm: float = 3.0
    length_mm: float = 10.0

    @classmethod
    def from_rig(cls, rig: Rig, part_id: str, thread: str, length_mm: float) -> "Screw":
        return cls(part_id, envelope(rig, part_id), part_colour("steel"), thread_diameter_mm(thread),
                   rig.dim(part_id, "head_diameter_mm"), rig.dim(part_id, "head_height_mm"), length_mm)

    def build(self) -> cq.Shape:
        head = cylinder(self.head_diameter_mm, self.head_height_mm, (0, 0, 0))
        shank = cylinder(self.diameter_mm, self.length_mm, (0, 0, -self.length_mm))
        return head.fuse(shank).clean()


@dataclass(frozen=True)
class Insert(VendorPart):
    outer_diameter_mm: float = 4.7
    length_mm: float = 4.3
    bore_mm: float = 3.0
    hole_diameter_mm: float = 3.9
    hole_extra_depth_mm: float = 0.5

    @classmethod
    def from_rig(cls, rig: Rig, part_id: str, thread: str) -> "Insert":
        x, y, _ = envelope(rig, part_id)
        return cls(part_id, (x, y, y), part_colour("brass"), y, x, thread_diameter_mm(thread),
                   rig.dim(part_id, "hole_diameter_mm"), rig.dim(part_id, "hole_extra_depth_mm"))

    @property
    def hole_depth_mm(self) -> float:
        return self.length_mm + self.hole_extra_depth_mm

    def build(self) -> cq.Shape:
        return tube(self.outer_diameter_mm, self.bore_mm, self.length_mm, (0, 0, -self.length_mm))

    def hole(self) -> cq.Shape:
        """The printed hole it is melted into (in the insert's frame)."""
        return cylinder(self.hole_diameter_mm, self.hole_depth_mm + 0.01, (0, 0, -self.hole_depth_mm))

    def melt_volume_mm3(self) -> float:
        """Plastic the insert displaces: the overlap an interference check must find, no more."""
        import math
        return math.pi / 4 * (self.outer_diameter_mm ** 2 - self.hole_diameter_mm ** 2) * self.length_mm
