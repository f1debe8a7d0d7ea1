"""Electronics of the power and sync chain: the DC-DC converter and the inline blade fuse holder
(boxes), the under-voltage cut-off (a module board with its mounting holes) and the Boson sync
breakout (a board on the core's rear connector).

Frame of the boxes and the board: origin at the centre of the bottom face. The converter's bottom M3
threads (``parts.dc_converter.mounting``) are tapped in its base plate (not cut here).
"""
from __future__ import annotations

from dataclasses import dataclass

import cadquery as cq

from platform_tools.rig import Rig

from cad.geom import Bounds, cylinder
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


@dataclass(frozen=True)
class BoardPart(BoughtPart):
    """A bare module board (the under-voltage cut-off): a board with its mounting holes and the block
    of its components on top, set in from the holes by the copper-free ring a screw head needs.
    Frame: origin at the centre of the board's underside, z up."""
    board_mm: float = 1.6
    hole_d_mm: float = 3.2
    keepout_mm: float = 6.0
    mount_uv_mm: tuple[tuple[float, float], ...] = ()

    @classmethod
    def from_rig(cls, rig: Rig, part_id: str) -> "BoardPart":
        ms = [m for m in rig.part(part_id).mounting if m.face.value == "bottom"]
        return cls(part_id, envelope(rig, part_id), part_colour("electronics"),
                   board_mm=rig.dim(part_id, "board_thickness_mm"), hole_d_mm=rig.dim(part_id, "hole_diameter_mm"),
                   keepout_mm=rig.dim(part_id, "hole_keepout_mm"), mount_uv_mm=ms[0].positions_mm if ms else ())

    def bounds(self) -> Bounds:
        x, y, z = self.size
        return Bounds((-x / 2, -y / 2, 0.0), (x / 2, y / 2, z))

    def mount_points(self) -> list[tuple[float, float, float]]:
        return [(u, v, 0.0) for u, v in self.mount_uv_mm]

    def components(self) -> Bounds:
        """The components' block: the board's width, between the holes' keep-out rings."""
        x, y, z = self.size
        half = min([x / 2] + [abs(u) - self.keepout_mm / 2 for u, _ in self.mount_uv_mm])
        return Bounds((-half, -y / 2, self.board_mm), (half, y / 2, z))

    def build(self) -> cq.Shape:
        x, y, _ = self.size
        board = Bounds((-x / 2, -y / 2, 0.0), (x / 2, y / 2, self.board_mm)).solid()
        for u, v, _ in self.mount_points():
            board = board.cut(cylinder(self.hole_d_mm, self.board_mm + 0.2, (u, v, -0.1)))
        return board.fuse(self.components().solid()).clean()


@dataclass(frozen=True)
class SyncBreakout(BoughtPart):
    """The Boson interface board on the core's rear connector: the USB-C socket and the 2-pin
    external-sync header come out of its rear face. Frame: origin at the centre of its front face
    (against the core's rear), x forward (towards the core), the board behind it (x < 0)."""

    @classmethod
    def from_rig(cls, rig: Rig, part_id: str) -> "SyncBreakout":
        return cls(part_id, envelope(rig, part_id), part_colour("electronics"))

    def bounds(self) -> Bounds:
        x, y, z = self.size
        return Bounds((-x, -y / 2, -z / 2), (0.0, y / 2, z / 2))

    def usb_socket(self) -> tuple[float, float, float]:
        """Where the USB-C plug goes in (its rear face, on the axis)."""
        return (-self.size[0], 0.0, 0.0)

    def sync_header(self) -> tuple[float, float, float]:
        """Where the sync harness plugs in: on the rear face, below the USB-C socket (the USB lead climbs
        away from the socket towards its run over the converter; the sync branch comes in under it)."""
        return (-self.size[0], 0.0, -self.size[2] / 4)
