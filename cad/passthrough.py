"""`check` "power and sync parts": what a builder meets first when fitting the cable gland, the cut-off
and the Boson sync breakouts, measured on the placed solids.

- **gland hole**: the hole's radius measured on the case tray's solid (the distance from the gland's
  axis, inside the floor, to the tray) equals the gland table's ``hole_diameter_mm`` / 2, no smaller
  than its thread, and smaller than the body's shoulder, which seals against the floor's outer face;
- **locknut socket**: a deep socket on the locknut (across its corners plus ``SOCKET_WALL_MM`` a side,
  ``SOCKET_LENGTH_MM`` long, up the gland's axis from the floor) clear of every part installed at the
  guide's step that fits the gland (or before it), the tray's own floor bosses included;
- **breakout plugs**: behind each sync breakout, the USB-C plug and the sync harness's connector need
  ``parts.boson_640.dims.usb_connector_clearance_mm`` of room (12 x 12 mm across, the Boson's own
  USB keep-out): that box clear of every part; and the board seated on the core's rear face;
- **cut-off board**: its underside on its bosses' tops.
"""
from __future__ import annotations

from OCP.BRepExtrema import BRepExtrema_DistShapeShape

import cadquery as cq

from cad.geom import Bounds
from cad.solids import TOUCH_MM3, bounds_of, box, common_volume_mm3, cylinder, moved

from .assembly import Assembly
from .assembly_order import load_steps
from .layout.power import SOCKET_WALL_MM    # the layout keeps the floor's bosses out of the socket's path

#: how far up from the floor the socket and its ratchet need a straight path (estimate)
SOCKET_LENGTH_MM = 45.0
#: the plug room behind a breakout is this wide and tall (the USB-C overmould and the 2-pin housing)
PLUG_ROOM_MM = 12.0
#: a measured size equals the table's within this (the B-rep is exact; this is float noise)
MEASURE_TOL_MM = 0.01


def _dist(a: cq.Shape, b: cq.Shape) -> float:
    d = BRepExtrema_DistShapeShape(a.wrapped, b.wrapped)
    d.Perform()
    return d.Value()


def gland_hole_diameter(asm: Assembly) -> float:
    """The gland's hole in the tray, measured: twice the distance from its axis (a segment inside the
    floor, between its faces) to the tray's solid."""
    p = asm.layout.power
    x, y, z = p.gland_pose.t
    wall = asm.layout.fits.wall
    axis = cq.Edge.makeLine(cq.Vector(x, y, z + 0.2 * wall), cq.Vector(x, y, z + 0.8 * wall))
    return 2 * _dist(axis, asm.node("case_lower").shape(asm.cache))


def socket_envelope(asm: Assembly) -> cq.Shape:
    """The locknut socket's path: up the gland's axis from the floor's inner face."""
    p = asm.layout.power
    x, y, _ = p.gland_pose.t
    floor = asm.layout.case.interior.lo[2]
    return cylinder(p.gland.nut_d_mm + 2 * SOCKET_WALL_MM, SOCKET_LENGTH_MM, (x, y, floor + 0.01))


def plug_rooms(asm: Assembly) -> dict[str, cq.Shape]:
    """Behind each breakout's rear face: the room its plugs take, by node name."""
    p, lay = asm.layout.power, asm.layout
    depth = lay.rig.dim(lay.cameras.core.part_id, "usb_connector_clearance_mm")
    x0 = -p.breakout.size[0]
    local = Bounds((x0 - depth, -PLUG_ROOM_MM / 2, -PLUG_ROOM_MM / 2), (x0 - 0.01, PLUG_ROOM_MM / 2, PLUG_ROOM_MM / 2))
    return {f"sync_breakout_{s}": moved(box(local), pose) for s, pose in p.breakout_poses.items()}


def _hits(env: cq.Shape, names, shapes: dict[str, cq.Shape]) -> list[str]:
    eb = bounds_of(env)
    out = []
    for name in names:
        s = shapes[name]
        if not eb.overlaps(bounds_of(s), 1e-6):
            continue
        v = common_volume_mm3(env, s)
        if v > TOUCH_MM3:
            out.append(f"{name} ({v:.1f} mm^3)")
    return out


def power_part_problems(asm: Assembly, extra: list[tuple[str, cq.Shape]] = ()) -> tuple[list[str], list[str], dict]:
    """(problems, details, data) of the gland, its socket path and the breakouts' plug room; ``extra``
    shapes (name, solid in the rig frame) count as installed parts."""
    p = asm.layout.power
    g = p.gland
    shapes = {n.name: n.shape(asm.cache) for n in asm.nodes}
    shapes.update(dict(extra))
    bad, details = [], []
    hole = gland_hole_diameter(asm)
    details.append(f"gland hole measured {hole:.2f} mm in case_lower (table {g.hole_d_mm:g} mm, thread {g.thread_d_mm:g} "
                   f"mm, shoulder {g.size[0]:g} mm across flats)")
    if abs(hole - g.hole_d_mm) > MEASURE_TOL_MM or hole < g.thread_d_mm or hole >= g.size[0]:
        bad.append(f"cable_gland: the floor's hole measures {hole:.2f} mm; the gland needs {g.hole_d_mm:g} mm "
                   f"(parts.{g.part_id}.dims.hole_diameter_mm), over its {g.thread_d_mm:g} mm thread and under its "
                   f"{g.size[0]:g} mm shoulder")
    names = [n.name for n in asm.nodes]
    steps = load_steps(names)
    at = next((s for s in steps if "cable_gland" in s.nodes), None)
    installed = [n for s in steps if at is not None and s.number <= at.number for n in s.nodes]
    # the tray itself counts too: the envelope starts 0.01 mm over the floor, so what of case_lower it meets
    # stands on the floor (a boss, a rib, a wall) in the socket's way
    installed = [n for n in installed if n != "cable_gland"] + [n for n, _ in extra]
    hits = _hits(socket_envelope(asm), installed, shapes)
    sock = g.nut_d_mm + 2 * SOCKET_WALL_MM
    details.append(f"locknut socket {sock:.1f} mm x {SOCKET_LENGTH_MM:g} mm up the gland's axis at step "
                   f"'{at.id if at else '?'}': " + (", ".join(hits) if hits else "clear"))
    if hits:
        bad.append(f"cable_gland: its locknut cannot be tightened: the socket's path is blocked by {', '.join(hits)}")
    others = [n for n in names if not n.startswith("sync_breakout_")] + [n for n, _ in extra]
    for name, room in plug_rooms(asm).items():
        seat = _dist(shapes[name], shapes[f"boson_{name.rsplit('_', 1)[1]}"])
        hits = _hits(room, others, shapes)
        details.append(f"{name}: {seat:.2f} mm from its Boson; plug room behind it: " + (", ".join(hits) or "clear"))
        if seat > MEASURE_TOL_MM:
            bad.append(f"{name}: not seated on its Boson's rear connector ({seat:.2f} mm away)")
        if hits:
            bad.append(f"{name}: no room to plug the USB-C and sync cables: blocked by {', '.join(hits)}")
    bad += cutoff_mount(asm)
    return bad, details, dict(gland_hole_mm=round(hole, 3), socket_mm=round(sock, 2))


def cutoff_mount(asm: Assembly) -> list[str]:
    """The cut-off board sits on its bosses: its underside on their tops."""
    p = asm.layout.power
    top = asm.layout.case.interior.lo[2] + max(h for *_, h in p.cutoff_seats)
    z = float(p.cutoff_pose.t[2])
    return [] if abs(z - top) < MEASURE_TOL_MM else [f"undervoltage_cutoff: its board is {z - top:+.2f} mm off its bosses"]
