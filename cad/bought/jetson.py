"""NVIDIA Jetson AGX Orin 64 GB developer kit.

Frame: origin at the centre of the bottom face (the feet), x forward, y left, z up; the I/O ports
are on the rear face (-x), in a band ``port_panel_height_mm`` tall from the bottom. Mounting: the
bottom M3 threads of ``parts.jetson_agx_orin.mounting`` (tapped in the devkit, not cut here).
"""
from __future__ import annotations

from dataclasses import dataclass

from platform_tools.rig import Rig

from cad.geom import Bounds
from cad.bought.base import BoughtPart, envelope, part_colour


@dataclass(frozen=True)
class JetsonOrin(BoughtPart):
    port_panel_height_mm: float = 0.0
    mount_uv_mm: tuple[tuple[float, float], ...] = ()
    mount_depth_mm: float = 0.0

    @classmethod
    def from_rig(cls, rig: Rig, part_id: str) -> "JetsonOrin":
        m = next(m for m in rig.part(part_id).mounting if m.face.value == "bottom")
        return cls(part_id, envelope(rig, part_id), part_colour("computer"),
                   port_panel_height_mm=rig.dim(part_id, "port_panel_height_mm"),
                   mount_uv_mm=m.positions_mm, mount_depth_mm=m.depth_mm)

    def bounds(self) -> Bounds:
        x, y, z = self.size
        return Bounds((-x / 2, -y / 2, 0.0), (x / 2, y / 2, z))

    def mount_points(self) -> list[tuple[float, float, float]]:
        return [(u, v, 0.0) for u, v in self.mount_uv_mm]

    def port_panel(self) -> Bounds:
        """The rear band where the ports are, 1 mm deep (a cut-out must clear it)."""
        x, y, _ = self.size
        return Bounds((-x / 2 - 1.0, -y / 2, 0.0), (-x / 2, y / 2, self.port_panel_height_mm))
