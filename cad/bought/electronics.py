"""Boxes of the power chain: the DC-DC converter and the inline blade fuse holder.

Frame of each: origin at the centre of its bottom face. The converter's bottom M3 threads
(``parts.dc_converter.mounting``) are tapped in its base plate (not cut here).
"""
from __future__ import annotations

from dataclasses import dataclass

from platform_tools.rig import Rig

from cad.geom import Bounds
from cad.bought.base import BoughtPart, envelope, part_colour


@dataclass(frozen=True)
class BoxPart(BoughtPart):
    mount_uv_mm: tuple[tuple[float, float], ...] = ()
    mount_depth_mm: float = 0.0

    @classmethod
    def from_rig(cls, rig: Rig, part_id: str) -> "BoxPart":
        ms = [m for m in rig.part(part_id).mounting if m.face.value == "bottom"]
        return cls(part_id, envelope(rig, part_id), part_colour("electronics"),
                   mount_uv_mm=ms[0].positions_mm if ms else (), mount_depth_mm=ms[0].depth_mm if ms else 0.0)

    def bounds(self) -> Bounds:
        x, y, z = self.size
        return Bounds((-x / 2, -y / 2, 0.0), (x / 2, y / 2, z))

    def mount_points(self) -> list[tuple[float, float, float]]:
        return [(u, v, 0.0) for u, v in self.mount_uv_mm]
