"""Stereolabs ZED Link Quad capture card (GMSL2), carried on the Orin devkit.

Frame: origin at the centre of its bottom face. A plain envelope: its connector to the devkit and the
GMSL2 sockets are inside it (placement on the devkit is an estimate; see docs/cad.md).
"""
from __future__ import annotations

from dataclasses import dataclass

from platform_tools.rig import Rig

from cad.geom import Bounds
from cad.bought.base import BoughtPart, envelope, part_colour


@dataclass(frozen=True)
class ZedLinkQuad(BoughtPart):
    @classmethod
    def from_rig(cls, rig: Rig, part_id: str) -> "ZedLinkQuad":
        return cls(part_id, envelope(rig, part_id), part_colour("card"))

    def bounds(self) -> Bounds:
        x, y, z = self.size
        return Bounds((-x / 2, -y / 2, 0.0), (x / 2, y / 2, z))
