"""The rig's key cables as swept paths: each route is a polyline of waypoints from the connector it
leaves to the connector it plugs into, laid with circular bends of its radius, swept with its cable's
diameter (``cad/bought/cables.yaml``), and checked:

- **bend radius**: every bend at least the cable's minimum (``bend_factor`` x diameter), and every bend
  fits between its neighbours: the tangent lengths ``R tan(theta / 2)`` of the two bends at a segment's
  ends (or a plug's straight length and one bend, at an end) must fit in the segment; otherwise the
  cable really bends tighter than the route says, and the report gives the largest radius that fits;
- **interference**: the swept cable intersected with every part of the assembly (the parts it plugs
  into too: a cable ends on its connector's face, it does not enter the part); anything above the
  interference check's 0.01 mm^3 is a clash, so a cable through a wall fails unless its path goes
  through an opening;
- **plugs**: the right-angle plugs' bodies in the Orin's rear ports (``plugs`` of the cable table) clear
  of every part and every other cable;
- **cable to cable**: no two swept cables overlap;
- **length**: path length (straights plus arcs ``R theta``) plus the kind's service slack, rounded up
  to the kind's next stock length (or to 10 mm for a kind cut from a reel); what the BOM buys.

Where the connectors are on the bought parts is an estimate wherever the rig gives no mounting face
for them (named below); the waypoints are computed from the layout, so they follow the parts.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import cadquery as cq
import numpy as np

from cad.bought.cables import CableKind, PlugEnvelope, cable_table
from cad.geom import Bounds, Vec3, placed_bounds
from cad.solids import TOUCH_MM3, bounds_of, box, common_volume_mm3

from .assembly import Assembly
from .cable_leads import ORIN_HEADER_Y_MM, ORIN_HEADER_Z_MM, button_leads, power_leads
from .cable_route import BEND_SPARE, Route

#: a turn under this (deg) is a straight run: no bend
STRAIGHT_DEG = 0.5
#: the capture card's connectors on its front face (+x), across it (y, from its centre): the GMSL2 socket
#: the ZED X uses and the trigger connector (J17). Estimates: the card is an envelope in the rig.
CARD_GMSL2_Y_MM, CARD_SYNC_Y_MM = 0.0, 15.0
#: the Wi-Fi card's antenna sockets, reached through the devkit's side (towards each antenna), this far up
#: from its bottom and at the antenna's x. Estimate.
ORIN_WIFI_Z_MM = 60.0
#: a fan's lead leaves its top face at its centre; it first rises this far above the fan's top
FAN_LEAD_RISE_MM = 12.0
#: the Makita dock adapter's lead leaves its side face towards the gland at its mid-height (estimate: the
#: adapter's lead exit is not in any public text; measure the adapter you buy and move it here)
ADAPTER_LEAD_EXIT_Z_SHARE = 0.5
#: each sync branch drops from the card's height this far inboard of its breakout's header (the USB lead's
#: lane), ahead of the Orin's front face, and crosses to the header under the USB lead
SYNC_DROP_INBOARD_MM = 10.0
#: the Orin devkit's rear ports the leads plug into, on its rear face (-x): across
#: (y, from its centre, + left), up from the devkit's bottom (z), the right-angle plug of the cable table
#: each takes and the side (+1 left, -1 right) its cable leaves the plug towards. Estimates: no port drawing
#: of the devkit is in the reference (measure a devkit); the USB-A ports the two Bosons use sit in the port
#: band's upper half, the DC jack low in it, so the DC lead runs under the right USB plug.
ORIN_REAR_PORTS = {
    "usb_left": (25.0, 23.0, "usb_a_right_angle", 1.0),
    "usb_right": (-25.0, 23.0, "usb_a_right_angle", -1.0),
    "dc_jack": (-5.0, 9.0, "dc_barrel_right_angle", -1.0),
}
#: the DC-DC converter's output terminals are on its rear end (-x), this share of the way across it (y) from its
#: outboard face; the DC lead comes in at the plug's height. Estimate: no page read shows where the TEP 150WI's
#: screw terminals sit (parts.dc_converter); look at a real one and move this
CONVERTER_OUT_SHARE = 0.5
#: the USB leads climb from the breakout to their run at this slope (deg), steep enough for the right one to
#: clear the converter's top before its front face (a shallower one needs more run than the fan plates leave)
USB_RISE_DEG = 75.0


@dataclass(frozen=True)
class Bend:
    corner: int                # index of the waypoint
    angle_deg: float
    radius_mm: float
    tangent_mm: float


@dataclass(frozen=True)
class Path:
    """A route's geometry: its bends, its length and the problems of its bends."""
    route: Route
    kind: CableKind
    bends: tuple[Bend, ...]
    length_mm: float
    problems: tuple[str, ...]

    @property
    def bought_mm(self) -> float | None:
        return self.kind.bought_length_mm(self.length_mm + self.route.extra_slack_mm)

    @property
    def slack_mm(self) -> float:
        """The kind's service slack and the route's own (the lid's)."""
        return self.kind.service_slack_mm + self.route.extra_slack_mm


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def path_of(route: Route, kind: CableKind) -> Path:
    """The bends of ``route`` at its radius, its length, and every way its bends break the cable's rules."""
    p = np.asarray(route.points, dtype=float)
    seg = np.diff(p, axis=0)
    lens = np.linalg.norm(seg, axis=1)
    if np.any(lens < 1e-6):
        raise ValueError(f"cable {route.name}: two waypoints coincide")
    d = seg / lens[:, None]
    R, need = route.radius_mm, kind.min_bend_radius_mm
    bends, problems = [], []
    tan_at = np.zeros(len(p))
    for i in range(1, len(p) - 1):
        theta = math.acos(float(np.clip(d[i - 1] @ d[i], -1.0, 1.0)))
        if math.degrees(theta) < STRAIGHT_DEG:
            continue
        tan_at[i] = R * math.tan(theta / 2)
        bends.append(Bend(i, math.degrees(theta), R, tan_at[i]))
    if R < need - 1e-9:
        problems.append(f"cable {route.name}: laid with {R:g} mm bends; a {kind.description} needs at least "
                        f"{need:g} mm ({kind.bend_factor:g} x {kind.diameter_mm:g} mm, {kind.source})")
    for s in range(len(seg)):
        used = tan_at[s] + tan_at[s + 1] + (kind.plug_mm if s == 0 and route.plugs[0] else 0.0) \
            + (kind.plug_mm if s == len(seg) - 1 and route.plugs[1] else 0.0)
        if used > lens[s] + 1e-6:
            # the largest radius the segment's bends fit in: scale the bends' share of the segment
            plugs = used - tan_at[s] - tan_at[s + 1]
            k = max(lens[s] - plugs, 0.0) / (tan_at[s] + tan_at[s + 1]) if tan_at[s] + tan_at[s + 1] > 0 else 0.0
            what = "its plug and bend" if s in (0, len(seg) - 1) else "the bends at both ends"
            problems.append(f"cable {route.name}: segment {s + 1} ({lens[s]:.1f} mm, waypoints {s}-{s + 1}) is too "
                            f"short for {what} ({used:.1f} mm): the cable bends to about {k * R:.1f} mm there, "
                            f"under the {need:g} mm it needs")
    length = float(lens.sum() - 2 * tan_at.sum()) + sum(b.radius_mm * math.radians(b.angle_deg) for b in bends)
    return Path(route, kind, tuple(bends), length, tuple(problems))


def centreline(route: Route) -> cq.Wire:
    """The route's centre line: straights and circular arcs of its radius, tangent to each other."""
    p = np.asarray(route.points, dtype=float)
    R = route.radius_mm
    edges, cur = [], p[0]
    for i in range(1, len(p) - 1):
        a, b = _unit(p[i] - p[i - 1]), _unit(p[i + 1] - p[i])
        theta = math.acos(float(np.clip(a @ b, -1.0, 1.0)))
        if math.degrees(theta) < STRAIGHT_DEG:
            continue
        t = R * math.tan(theta / 2)
        t0, t1 = p[i] - a * t, p[i] + b * t
        centre = t0 + R * _unit(b - a * (a @ b))          # the arc's centre, R from t0 towards the turn
        mid = centre + R * _unit(p[i] - centre)
        if np.linalg.norm(t0 - cur) > 1e-6:
            edges.append(cq.Edge.makeLine(cq.Vector(*cur), cq.Vector(*t0)))
        edges.append(cq.Edge.makeThreePointArc(cq.Vector(*t0), cq.Vector(*mid), cq.Vector(*t1)))
        cur = t1
    edges.append(cq.Edge.makeLine(cq.Vector(*cur), cq.Vector(*p[-1])))
    return cq.Wire.assembleEdges(edges)


def sweep(route: Route, kind: CableKind) -> cq.Shape:
    """The cable as a solid: a circle of its diameter swept along the centre line."""
    p = np.asarray(route.points, dtype=float)
    path = centreline(route)
    d0 = _unit(p[1] - p[0])
    circle = cq.Wire.makeCircle(kind.diameter_mm / 2, cq.Vector(*p[0]), cq.Vector(*d0))
    return cq.Solid.sweep(circle, [], path, True, False, None, "round")


# ----------------------------------------------------------------------------- the routes
def routes(asm: Assembly) -> list[Route]:
    """The key cables of the rig, their waypoints computed from the layout."""
    lay = asm.layout
    table = cable_table().kinds
    R = lambda kind: table[kind].min_bend_radius_mm
    zed, card, orin = lay.cameras.zed_box, lay.compute.card_box, lay.compute.orin_box
    out = []
    # GMSL2: out of the ZED X's rear (its centre) backwards, an S-bend up to the card's front socket
    k = table["gmsl2_coax"]
    a = np.array([zed.lo[0], CARD_GMSL2_Y_MM, zed.centre[2]])
    b = np.array([card.hi[0], CARD_GMSL2_Y_MM, card.centre[2]])
    p1, p2 = _s_bend(a, b, k.plug_mm, R("gmsl2_coax"))
    out.append(Route("gmsl2", "gmsl2_coax", "gmsl2_cable", ("zed_x", "zed_link_quad"), (tuple(a), p1, p2, tuple(b)),
                     R("gmsl2_coax")))
    # sync harness: from the card's trigger connector forwards over the devkit, across to the branch's drop
    # lane ahead of the Orin's front, down it under the USB lead's height, and across to each breakout's header,
    # plugged in from behind (cad/cables.py has no route over another: the cable-to-cable check)
    ks = table["sync_pair"]
    Rs = R("sync_pair")
    start = np.array([card.hi[0], CARD_SYNC_Y_MM, card.centre[2]])
    x_drop = orin.hi[0] + lay.fits.clear + ks.diameter_mm / 2 + Rs
    for side, pose in lay.power.breakout_poses.items():
        hdr = pose.apply(np.array(lay.power.breakout.sync_header()))
        run_x = hdr[0] - ks.plug_mm - Rs    # a bend's tangent is at most R (turns up to 90 deg)
        y_drop = float(hdr[1]) - np.sign(hdr[1]) * SYNC_DROP_INBOARD_MM
        pts = (tuple(start), (x_drop, start[1], start[2]), (x_drop, y_drop, start[2]), (x_drop, y_drop, float(hdr[2])),
               (run_x, float(hdr[1]), float(hdr[2])), tuple(hdr))
        out.append(Route(f"sync_{side}", "sync_pair", "sync_harness", ("zed_link_quad", f"sync_breakout_{side}"), pts,
                         Rs))
    # fan leads: up from the fan's top, across to the Orin's front face, into the 40-pin header
    kf = table["fan_lead"]   # the fan's own lead leaves its body: a plug only at the header
    for side, f in lay.cooling.fans.items():
        top = np.array([f.box.centre[0], f.box.centre[1], f.box.hi[2]])
        z_run = top[2] + FAN_LEAD_RISE_MM
        hdr = np.array([orin.hi[0], f.sign * ORIN_HEADER_Y_MM, orin.lo[2] + ORIN_HEADER_Z_MM])
        pts = (tuple(top), (top[0], top[1], z_run), (top[0], hdr[1], z_run), (hdr[0] + kf.plug_mm + R("fan_lead"), hdr[1], hdr[2]),
               tuple(hdr))
        out.append(Route(f"fan_lead_{side}", "fan_lead", None, (f"fan_{side}", "jetson_agx_orin"), pts, R("fan_lead"),
                         plugs=(False, True)))
    # Wi-Fi pigtails: down from each antenna bulkhead's body under the roof, across into the devkit's side
    for name, (part, pose) in lay.controls.items():
        if not name.startswith("wifi_antenna"):
            continue
        body = placed_bounds(part.bounds(), pose)
        a = np.array([pose.t[0], pose.t[1], body.lo[2]])
        side_y = orin.hi[1] if a[1] > 0 else orin.lo[1]
        z = orin.lo[2] + ORIN_WIFI_Z_MM
        pts = (tuple(a), (a[0], a[1], z), (a[0], side_y, z))
        out.append(Route(f"pigtail_{name.rsplit('_', 1)[1]}", "ufl_pigtail", "wifi_pigtail", (name, "jetson_agx_orin"),
                         pts, R("ufl_pigtail")))
    out.append(battery_lead(asm))
    out += usb_leads(asm)
    out.append(dc_lead(asm))
    out += power_leads(asm, out)
    out += button_leads(asm)
    return out


def plug_at_port(orin_box: Bounds, port: str) -> tuple[PlugEnvelope, Bounds, tuple[float, float, float], float]:
    """The right-angle plug in one of the Orin's rear ports (``ORIN_REAR_PORTS``): its envelope, its body's
    box behind the port face, where its cable leaves that body, and the side (+-1 in y) it leaves towards."""
    y, z_up, plug_id, side = ORIN_REAR_PORTS[port]
    plug = cable_table().plugs[plug_id]
    x, z = orin_box.lo[0], orin_box.lo[2] + z_up
    ya, yb = sorted((y - side * plug.width_mm / 2, y + side * plug.reach_mm))
    body = Bounds((x - plug.depth_mm, ya, z - plug.height_mm / 2), (x, yb, z + plug.height_mm / 2))
    return plug, body, (x - plug.exit_depth_mm, y + side * plug.reach_mm, z), side


def _slope(dz: float, R: float, slope_deg: float) -> float:
    """The slope (rad) of a climb or drop of ``dz`` between two bends of radius ``R``: ``slope_deg``, or
    shallower when the climb is too short for both bends at that slope (the segment between the corners
    must hold both tangents, with 2 % to spare)."""
    theta = math.radians(slope_deg)
    while theta > math.radians(STRAIGHT_DEG) and abs(dz) / math.sin(theta) < 2 * R * math.tan(theta / 2) * BEND_SPARE:
        theta -= math.radians(1.0)
    return theta


def _rise(x0: float, z0: float, z1: float, R: float, slope_deg: float) -> tuple[tuple[float, float], tuple[float, float]]:
    """The corners (x, z) of a climb from height ``z0`` to ``z1`` going -x whose first bend starts at ``x0``."""
    dz = abs(z1 - z0)
    theta = _slope(dz, R, slope_deg)
    xa = x0 - R * math.tan(theta / 2)
    return (xa, z0), (xa - dz / math.tan(theta), z1)


def usb_leads(asm: Assembly) -> list[Route]:
    """Each Boson's USB lead, from its breakout's USB-C socket to its USB-A port on the Orin's rear panel.
    Out of the socket straight back (the plug), a climb to the lead's run (the port's height, or over any
    power part in its lane: the converter on the right), back beside the devkit in the breakout's lane,
    down to the port's height ahead of the rear wall, and one bend across the rear bay into the right-angle
    plug's side. The rear wall stands the deepest plug behind the port face (cad/layout/case.py)."""
    lay = asm.layout
    k = cable_table().kinds["usb_lead"]
    R, r = k.min_bend_radius_mm, k.diameter_mm / 2
    orin, clear = lay.compute.orin_box, lay.fits.clear
    inside_y = lay.case.interior.hi[1] - r - clear       # how far out a lead may run (the interior is symmetric)
    obstacles = [lay.power.converter_box, placed_bounds(lay.power.cutoff.bounds(), lay.power.cutoff_pose),
                 placed_bounds(lay.power.fuse.bounds(), lay.power.fuse_pose)]
    out = []
    for side, pose in lay.power.breakout_poses.items():
        s0 = np.asarray(pose.apply(np.array(lay.power.breakout.usb_socket())), dtype=float)
        port = f"usb_{side}"
        plug, body, exit_pt, port_side = plug_at_port(orin, port)
        y, z0, zp = float(s0[1]), float(s0[2]), exit_pt[2]
        lane = [b for b in obstacles if b.lo[1] - r - clear < y < b.hi[1] + r + clear]
        z_run = max([zp] + [b.hi[2] + r + clear for b in lane])
        (x1, _), (x2, _) = _rise(s0[0] - k.plug_mm, z0, z_run, R, USB_RISE_DEG)
        xc = exit_pt[0]
        # the lane at the rear: the bay's bend (from -x into -+y) arcs forward past the devkit's rear corner
        ahead = xc + R - orin.lo[0]
        y_rear = orin.hi[1] + r + clear + (R - math.sqrt(R * R - ahead * ahead) if 0 < ahead < R else 0.0)
        y_rear = max(abs(y), y_rear) * math.copysign(1.0, y)
        pts = [tuple(s0), (x1, y, z0), (x2, y, z_run)]
        into_bay = [(xc, y_rear, zp), tuple(exit_pt)]
        if z_run - zp > 1e-6:   # down to the port's height ahead of the bay's last bend
            down = _slope(z_run - zp, R, USB_RISE_DEG)
            x4 = xc + R + R * math.tan(down / 2) + clear
            x3 = x4 + (z_run - zp) / math.tan(down)
            # the part it climbed over reaches back past that drop (the converter beside the devkit): the lead
            # runs on over it to the rear bay and comes down in the bay, into the plug's side (when no descent
            # fits there, the drop ahead of the bay stays, and the cable check names the part in its way)
            bay = (_bay_descent(xc, z_run, exit_pt, port_side, R, USB_RISE_DEG, inside_y)
                   if any(b.lo[0] - r - clear < x3 + R * math.tan(down / 2) for b in lane) else None)
            if bay:
                into_bay = bay
            else:
                pts += [(x3, y_rear, z_run), (x4, y_rear, zp)]
        pts += into_bay
        out.append(Route(port, "usb_lead", "boson_usb_cable", (f"sync_breakout_{side}", "jetson_agx_orin"), tuple(pts),
                         R, plugs=(True, False), envelopes=((f"{port} plug ({plug.description})", body),)))
    return out


def _bay_descent(xc: float, z_run: float, exit_pt: Vec3, side: float, R: float, slope_deg: float,
                 y_max: float) -> list[Vec3] | None:
    """The corners of a lead that comes back along its lane at ``z_run`` over the rear bay (x = ``xc``, the
    plug's cable exit) and comes down in the bay's plane to the right-angle plug, whose cable leaves it
    towards ``side`` (+-1 in y): one corner turns it from its run down and inboard, the next one into the
    plug's side. The descent is ``slope_deg`` from the horizontal, or shallower until the two bends fit
    between the corners (the first turns about 90 deg, the second the slope), with 2 % to spare.
    None when no slope fits or the upper corner would leave the interior (beyond ``y_max``)."""
    _, ye, zp = exit_pt
    dz = z_run - zp
    theta = math.radians(slope_deg)
    while theta > math.radians(STRAIGHT_DEG):
        if dz / math.sin(theta) >= BEND_SPARE * (R + R * math.tan(theta / 2)):
            break
        theta -= math.radians(1.0)
    else:
        return None
    yp = ye + side * BEND_SPARE * R * math.tan(theta / 2)     # the last bend's tangent fits before the plug's side
    yq = yp + side * dz / math.tan(theta)
    if abs(yq) > y_max:
        return None
    return [(xc, yq, z_run), (xc, yp, zp), tuple(exit_pt)]


def dc_lead(asm: Assembly) -> Route:
    """The Orin's DC lead: from the right-angle barrel plug in its DC jack across the rear bay (low in the
    port band, under the right USB plug), one bend forward into the converter's lane, and on to the
    converter's output terminals on its rear end (``CONVERTER_OUT_SHARE`` across it), where the pigtail's
    bare end is clamped: straight in at the plug's height when the rear end spans it, else a climb to the
    terminals at the rear end's middle."""
    lay = asm.layout
    k = cable_table().kinds["dc_lead"]
    R, r = k.min_bend_radius_mm, k.diameter_mm / 2
    plug, body, exit_pt, _ = plug_at_port(lay.compute.orin_box, "dc_jack")
    conv = lay.power.converter_box
    xc, zp = exit_pt[0], exit_pt[2]
    y_out = conv.lo[1] + CONVERTER_OUT_SHARE * (conv.hi[1] - conv.lo[1])
    corner = (xc, y_out, zp)
    if conv.lo[2] + r <= zp <= conv.hi[2] - r:
        pts = (tuple(exit_pt), corner, (conv.lo[0], y_out, zp))
    else:
        out_pt = (conv.lo[0], y_out, conv.centre[2])
        level = (out_pt[0] - R, y_out, out_pt[2])       # level with the output a radius behind it
        pts = (tuple(exit_pt), corner, level, out_pt)
    return Route("dc_lead", "dc_lead", "orin_dc_plug", ("jetson_agx_orin", "dc_converter"), pts, R,
                 plugs=(False, False), envelopes=((f"dc_jack plug ({plug.description})", body),))


def battery_lead(asm: Assembly) -> Route:
    """The dock adapter's lead, up into the case through the cable gland. The gland must be entered straight
    along its axis from below (its seal grips the cable over the dome), and the gland stands outboard of
    the adapter: so the lead leaves the adapter's side towards the gland ``2 R`` ahead of it (R the lead's
    minimum bend), drops ``2 R`` beside the adapter, runs back under the gland and rises through it (its
    last bend ends below the dome), and ends ``R`` above the locknut, where it is spliced to the fuse
    holder's lead (no plug at either end: the adapter's own lead, cut to length)."""
    lay = asm.layout
    kind = cable_table().kinds["battery_lead"]
    R = kind.min_bend_radius_mm
    g, gp = lay.power.gland, lay.power.gland_pose
    ad = placed_bounds(lay.power.adapter.bounds(), lay.power.adapter_pose)
    xg, yg, zf = (float(v) for v in gp.t)
    sy = 1.0 if yg > ad.centre[1] else -1.0
    x_e = xg + 2 * R if xg + 2 * R <= ad.hi[0] else xg - 2 * R
    z_e = ad.lo[2] + ADAPTER_LEAD_EXIT_Z_SHARE * (ad.hi[2] - ad.lo[2])
    side = ad.hi[1] if sy > 0 else ad.lo[1]
    drop = z_e - 2 * R
    top = zf + g.nut_top_mm() + R
    pts = ((x_e, side, z_e), (x_e, yg, z_e), (x_e, yg, drop), (xg, yg, drop), (xg, yg, top))
    return Route("battery_lead", "battery_lead", None, ("makita_adapter", "cable_gland"), pts, R, plugs=(False, False))


def _s_bend(a: np.ndarray, b: np.ndarray, plug: float, R: float) -> tuple[Vec3, Vec3]:
    """The two corners of an S-bend from ``a`` (leaving along -x) to ``b`` (arriving along -x), each
    corner after a plug's straight length and its own bend's tangent (solved by fixed point)."""
    t = 0.0
    for _ in range(50):
        x1, x2 = a[0] - plug - t, b[0] + plug + t
        theta = math.atan2(math.hypot(b[1] - a[1], b[2] - a[2]), max(x1 - x2, 1e-6))
        t = R * math.tan(theta / 2)
    return (x1, float(a[1]), float(a[2])), (x2, float(b[1]), float(b[2]))


# ----------------------------------------------------------------------------- the check
@dataclass(frozen=True)
class CableReport:
    paths: list[Path]
    problems: list[str]
    details: list[str]


def cable_report(asm: Assembly, extra_routes: list[Route] = (), only: list[Route] | None = None) -> CableReport:
    """Every route's bends, clashes and length; ``only`` replaces the rig's routes, ``extra_routes`` add to them."""
    table = cable_table().kinds
    rs = (list(only) if only is not None else routes(asm)) + list(extra_routes)
    shapes = [(n.name, n.shape(asm.cache)) for n in asm.nodes]
    boxes = {name: bounds_of(s) for name, s in shapes}
    paths, problems, details = [], [], []
    gland = asm.layout.power.gland
    if abs(table["battery_lead"].diameter_mm - gland.cable_d_mm) > 1e-9:
        problems.append(f"cad/bought/cables.yaml: kinds.battery_lead.diameter_mm is {table['battery_lead'].diameter_mm:g} mm "
                        f"but parts.{gland.part_id}.dims.cable_diameter_mm (the lead the gland is chosen for) is "
                        f"{gland.cable_d_mm:g} mm: one of them is wrong")
    usb, room = table.get("usb_lead"), asm.layout.rig.dim(asm.layout.cameras.core.part_id, "usb_connector_clearance_mm")
    if usb is not None and usb.plug_mm > room + 1e-9:
        problems.append(f"cad/bought/cables.yaml: kinds.usb_lead.plug_mm is {usb.plug_mm:g} mm but the room behind each "
                        f"breakout is parts.{asm.layout.cameras.core.part_id}.dims.usb_connector_clearance_mm = {room:g} mm")
    # (what, its harness, solid): a plug body and its own cable touch by design (the cable leaves its face), and
    # the branches of one harness (one catalogue entry, one start: the sync Y) share their trunk
    swept: list[tuple[str, str, cq.Shape]] = []
    for r in rs:
        if r.kind not in table:
            raise KeyError(f"cable {r.name}: kind {r.kind!r} is not in cad/bought/cables.yaml")
        pth = path_of(r, table[r.kind])
        paths.append(pth)
        problems += list(pth.problems)
        try:
            solid = sweep(r, table[r.kind])
        except Exception as e:   # OpenCascade cannot sweep a self-overlapping centre line: its bends' problems say why
            problems.append(f"cable {r.name}: its path cannot be swept ({type(e).__name__}); see its bends above")
            continue
        hits = _hits(solid, shapes, boxes)
        if hits:
            problems.append(f"cable {r.name} ({r.ends[0]} to {r.ends[1]}) runs through {', '.join(hits)}")
        for what, b in r.envelopes:
            ph = _hits(box(b), shapes, boxes)
            if ph:
                problems.append(f"cable {r.name}: its {what} runs into {', '.join(ph)}")
            swept.append((f"the {what}", _harness(r), box(b)))
        swept.append((f"cable {r.name}", _harness(r), solid))
        bought = pth.bought_mm
        details.append(f"{r.name}: {table[r.kind].description}, {r.ends[0]} -> {r.ends[1]}: {pth.length_mm:.0f} mm + "
                       f"{pth.slack_mm:g} mm slack" + (" (the lid's included)" if r.extra_slack_mm else "") + " -> "
                       + (f"{bought:.0f} mm" if bought is not None else "LONGER THAN ANY STOCK LENGTH")
                       + f"; {len(pth.bends)} bends of {r.radius_mm:g} mm (min {table[r.kind].min_bend_radius_mm:g})"
                       + ("" if hits else "; clear"))
        if bought is None:
            problems.append(f"cable {r.name}: {pth.length_mm:.0f} mm + slack is longer than every stock length of "
                            f"{r.kind} ({', '.join(f'{s:g}' for s in table[r.kind].stock_lengths_mm)} mm)")
    problems += _cable_clashes(swept)
    return CableReport(paths, problems, details)


def _hits(solid: cq.Shape, shapes: list[tuple[str, cq.Shape]], boxes: dict[str, Bounds]) -> list[str]:
    """Every part ``solid`` overlaps by more than a touch, with the volume."""
    sb, hits = bounds_of(solid), []
    for name, s in shapes:
        if not sb.overlaps(boxes[name], 1e-6):
            continue
        v = common_volume_mm3(solid, s)
        if v > TOUCH_MM3:
            hits.append(f"{name} ({v:.1f} mm^3)")
    return hits


def _harness(r: Route) -> str:
    """What a route is part of: its catalogue entry and start point (the branches of a Y harness), or itself."""
    return f"{r.catalogue}@{np.round(r.points[0], 3).tolist()}" if r.catalogue else r.name


def _cable_clashes(swept: list[tuple[str, str, cq.Shape]]) -> list[str]:
    """Every two cables (or a cable and a plug body) of different harnesses that overlap by more than a touch."""
    out, bbs = [], [bounds_of(s) for _, _, s in swept]
    for i in range(len(swept)):
        for j in range(i + 1, len(swept)):
            (a, ra, sa), (b, rb, sb) = swept[i], swept[j]
            if ra == rb or not bbs[i].overlaps(bbs[j], 1e-6):
                continue
            v = common_volume_mm3(sa, sb)
            if v > TOUCH_MM3:
                out.append(f"{a} and {b} overlap ({v:.1f} mm^3): one of them must move")
    return out


def cable_lengths(asm: Assembly) -> list[dict]:
    """Per route what the BOM writes: name, kind, catalogue entry, route, slack and bought length (mm)."""
    table = cable_table().kinds
    out = []
    for r in routes(asm):
        pth = path_of(r, table[r.kind])
        out.append(dict(route=r.name, kind=r.kind, description=table[r.kind].description, catalogue=r.catalogue,
                        ends=list(r.ends), route_mm=round(pth.length_mm, 1), slack_mm=pth.slack_mm,
                        bought_mm=pth.bought_mm, stock=bool(table[r.kind].stock_lengths_mm),
                        min_bend_radius_mm=table[r.kind].min_bend_radius_mm, source=table[r.kind].source))
    return out
