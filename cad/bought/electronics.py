"""Electronics of the power and sync chain: the DC-DC converter (a box), the blade fuse holder (a body
on a screw tab at each end), the under-voltage cut-off (a module board with its mounting holes) and the
Boson sync breakout (a board on the core's rear connector).

Frame of the boxes and the board: origin at the centre of the bottom face. The converter's bottom M3
threads (``parts.dc_converter.mounting``) are tapped in its base plate (not cut here).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from platform_tools.rig import Rig

from cad.geom import Bounds
from cad.bought.base import BoughtPart, envelope, part_colour

if TYPE_CHECKING:
    import cadquery as cq


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


#: The fuse holder's screw tabs, used while the rig gives the holder no ``mounting`` (``parts.<fuse>.mounting``,
#: face bottom, wins once written): an ATO holder with a screw tab at each end of its body. No datasheet
#: or drawing of such a holder was read (bom/parts.yaml blade_fuse: no holder with a part number was
#: found), so every figure here is an ESTIMATE of a common one: measure the holder bought and write its
#: tab holes into config/rig.yaml before printing the tray.
#: tab holes' centres apart, along the holder (estimate)
FUSE_TAB_HOLE_SPACING_MM = 32.0
#: the tab holes' diameter (estimate: an M3 clearance)
FUSE_TAB_HOLE_D_MM = 3.5
#: the tabs' thickness: what the screw clamps (estimate)
FUSE_TAB_THICKNESS_MM = 2.0
#: the tabs' width across the holder (estimate)
FUSE_TAB_WIDTH_MM = 10.0
#: the flat of each tab from its hole's centre in to the body (estimate: room for a head 8 mm across)
FUSE_TAB_FLAT_MM = 4.0


@dataclass(frozen=True)
class FuseHolder(BoxPart):
    """The blade fuse holder: its body between two screw tabs that lie on the floor's bosses, each with a
    through hole. Frame: origin at the centre of the tabs' underside, x along the holder, z up. ``source``
    says where the tab holes come from (the rig's mounting, or the estimates above)."""
    tab_mm: float = FUSE_TAB_THICKNESS_MM
    hole_d_mm: float = FUSE_TAB_HOLE_D_MM
    tab_width_mm: float = FUSE_TAB_WIDTH_MM
    thread: str | None = None      # the screw the rig's mounting names; None: the floor insert's
    source: str = ""

    @classmethod
    def from_rig(cls, rig: Rig, part_id: str) -> "FuseHolder":
        ms = [m for m in rig.part(part_id).mounting if m.face.value == "bottom"]
        if ms:
            m = ms[0]
            return cls(part_id, envelope(rig, part_id), part_colour("electronics"), mount_uv_mm=tuple(m.positions_mm),
                       tab_mm=m.depth_mm, thread=m.thread,
                       source=f"parts.{part_id}.mounting ({m.source}, {m.confidence.value})")
        s = FUSE_TAB_HOLE_SPACING_MM / 2
        return cls(part_id, envelope(rig, part_id), part_colour("electronics"), mount_uv_mm=((-s, 0.0), (s, 0.0)),
                   source="estimate (cad/bought/electronics.py FUSE_TAB_*: no holder drawing read)")

    def body(self) -> Bounds:
        """The holder's body between the tabs' flats (its tab holes' centres on the tabs' underside are
        BoxPart's ``mount_points``, where the screws' inserts are, below)."""
        x, y, z = self.size
        half = min([x / 2] + [abs(u) - FUSE_TAB_FLAT_MM for u, _ in self.mount_uv_mm])
        return Bounds((-half, -y / 2, 0.0), (half, y / 2, z))

    def build(self) -> cq.Shape:
        from cad.solids import box, cylinder
        x, _, _ = self.size
        w = self.tab_width_mm
        tabs = box(Bounds((-x / 2, -w / 2, 0.0), (x / 2, w / 2, self.tab_mm)))
        for u, v, _ in self.mount_points():
            tabs = tabs.cut(cylinder(self.hole_d_mm, self.tab_mm + 0.2, (u, v, -0.1)))
        return tabs.fuse(box(self.body())).clean()


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
        from cad.solids import box, cylinder
        x, y, _ = self.size
        board = box(Bounds((-x / 2, -y / 2, 0.0), (x / 2, y / 2, self.board_mm)))
        for u, v, _ in self.mount_points():
            board = board.cut(cylinder(self.hole_d_mm, self.board_mm + 0.2, (u, v, -0.1)))
        return board.fuse(box(self.components())).clean()


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
