"""The holes a part's drawing lists (cad/drawings.py): found on the solid, located, labelled.

Every hole the joints cut (and the cable gland's) is matched to the cylindrical face of the solid with
its diameter whose axis runs through it, plus every other full-circle cylindrical cavity of the solid (a
lens bore, a handle's access hole, a window, a panel part's cut-out). Each :class:`HoleMark` carries its
view, its ordinates from that view's datum (the part's lowest coordinates on the view's two axes), the
face it is drilled from, diameter, depth, position tolerance (the stack-up's "printed/machined hole
position" term, cad/datums.py) and what it is for, from the joint's role for it or the part's spec;
:func:`hole_spacing` gives the heat sink's two tapped holes whose spacing the drawing dimensions.
"""
from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass

import cadquery as cq
import numpy as np
from OCP.gp import gp_Pnt

from .assembly import Assembly, Node
from .solids import bounds_of

#: a B-rep cylinder and a hole of the model are the same feature when their radii agree to this (mm) and
#: the cylinder's axis passes this close to the hole's origin (mm)
RADIUS_TOL_MM, AXIS_TOL_MM = 2e-3, 0.05
#: a cylindrical cavity the model does not list counts as a hole when its faces go this far round (deg)
FULL_CIRCLE_DEG = 359.0
#: ... and is deeper than this (mm): the lead of a neighbour's hole tool (0.01 mm past a face) is no hole
MIN_DEPTH_MM = 0.05
#: the view a hole is seen end-on in, by its axis
VIEW_OF_AXIS = {0: "side", 1: "elevation", 2: "plan"}
#: a view's paper axes as indices of the part frame
VIEW_AXES = {"plan": (0, 1), "elevation": (0, 2), "side": (1, 2)}


@dataclass(frozen=True)
class Cylinder:
    """Coaxial cylindrical faces of one radius read from the B-rep: a hole when concave (the material
    outside it). ``point`` is on the axis, ``axis`` a unit vector with its largest component positive,
    ``extent`` (lo, hi) the faces' reach along it from ``point`` (mm), ``span_deg`` how far round they go."""
    radius: float
    point: tuple[float, float, float]
    axis: tuple[float, float, float]
    extent: tuple[float, float]
    span_deg: float
    concave: bool


def cylinders(shape: cq.Shape) -> list[Cylinder]:
    """Every cylindrical feature of ``shape`` (its faces grouped by radius and axis line)."""
    from OCP.BRepAdaptor import BRepAdaptor_Surface
    from OCP.BRepGProp import BRepGProp_Face
    from OCP.BRepTools import BRepTools
    from OCP.gp import gp_Vec
    faces = []
    for f in shape.Faces():
        if f.geomType() != "CYLINDER":
            continue
        ad = BRepAdaptor_Surface(f.wrapped)
        cyl = ad.Cylinder()
        loc, d = cyl.Axis().Location(), cyl.Axis().Direction()
        p, a = np.array([loc.X(), loc.Y(), loc.Z()]), np.array([d.X(), d.Y(), d.Z()])
        u0, u1, v0, v1 = BRepTools.UVBounds_s(f.wrapped)
        pt, n = gp_Pnt(), gp_Vec()
        BRepGProp_Face(f.wrapped).Normal((u0 + u1) / 2, (v0 + v1) / 2, pt, n)
        q = np.array([pt.X(), pt.Y(), pt.Z()]) - p
        radial = q - (q @ a) * a
        concave = float(np.array([n.X(), n.Y(), n.Z()]) @ radial) < 0
        if a[np.argmax(np.abs(a))] < 0:
            a, (v0, v1) = -a, (-v1, -v0)
        p = p - (p @ a) * a                       # the axis line's foot (closest point to the origin)
        faces.append((cyl.Radius(), p, a, v0 + 0.0, v1 + 0.0, math.degrees(u1 - u0), concave))
    groups: list[list] = []
    for r, p, a, v0, v1, span, concave in faces:
        for g in groups:
            if (abs(g[0] - r) < RADIUS_TOL_MM and g[2] @ a > 1 - 1e-9 and np.linalg.norm(g[1] - p) < 1e-3
                    and g[6] == concave):
                g[3], g[4], g[5] = min(g[3], v0), max(g[4], v1), g[5] + span
                break
        else:
            groups.append([r, p, a, v0, v1, span, concave])
    return [Cylinder(float(r), tuple(map(float, p)), tuple(map(float, a)), (float(v0), float(v1)), float(span), concave)
            for r, p, a, v0, v1, span, concave in groups]


def _off_axis(c: Cylinder, point) -> float:
    q = np.asarray(point, float) - np.asarray(c.point)
    a = np.asarray(c.axis)
    return float(np.linalg.norm(q - (q @ a) * a))


@dataclass(frozen=True)
class HoleMark:
    """One hole of a drawing: its id, where its axis crosses the view it is seen end-on in (mm from that
    view's lower-left corner, the datum), the face it is drilled from, its size and what it is for."""
    id: str
    view: str                     # plan | elevation | side
    at: tuple[float, float]       # ordinates along the view's two axes from its datum corner (mm)
    centre: tuple[float, float, float]   # the axis point in the part frame (mm), for the record
    face: str                     # the face it is drilled from ("-z": the underside)
    diameter: float
    depth: float
    purpose: str                  # short: "clearance M3, normal fit", "insert M3 ..."
    note: str                     # long: the hole table's group text
    tolerance: float              # its position tolerance (mm, +-)
    on_solid: bool                # its axis was read from the B-rep (else: the layout's, and it says so)
    joint: str = ""               # the joint that cuts it ("" for a feature of the part)


def _stack_up_term(asm: Assembly, name: str) -> float:
    """The +- value the tolerance stack-up (cad/tolerances.py, on cad/datums.py's locations) gives the term
    ``name`` ("machined hole position", "printed hole position")."""
    from .datums import camera_locations
    for chain in camera_locations(asm.layout).values():
        for loc in chain:
            for f in loc.features:
                for c in f.contacts:
                    for n, v, _ in c.terms:
                        if n == name:
                            return float(v)
    raise KeyError(f"the stack-up has no term {name!r}")


def hole_position_tolerance(asm: Assembly, node: Node) -> float:
    return _stack_up_term(asm, "machined hole position" if node.category == "machined" else "printed hole position")


def _purpose(asm: Assembly, j, h) -> tuple[str, str]:
    """(short, long) of what hole ``h`` of joint ``j`` is for, from the joint's role for it."""
    fits, rig = asm.layout.fits, asm.rig
    clr = fits.screw_hole_mm(j.thread)
    if h.part == j.host:
        if j.kind == "insert":
            pn = rig.part(j.insert.part_id).part_number if j.insert is not None else ""
            return f"insert {j.thread} {pn}".strip(), f"heat-set insert {pn}".strip()
        if j.kind == "tapped":
            return f"tap {j.thread} (tap drill)", f"tap drill, then tap {j.thread}"
        if j.kind == "self_tap":
            return f"pilot, {j.thread} self-tap", f"pilot hole for the {j.thread} self-tapping screw"
    if abs(h.diameter - clr) < 1e-6:
        name = j.thread.split()[0]
        fit = (f"{rig.desc.enclosure.screw_fit} fit" if name in fits.screw_holes_mm
               else f"+{2 * fits.sliding_mm:g} mm sliding play")
        return f"clearance {j.thread}", f"{j.thread} clearance, {fit}"
    if h.diameter > clr:
        coaxial = any(o is not h and o.part == h.part and abs(o.diameter - clr) < 1e-6 for o in j.holes)
        if coaxial:
            return f"counterbore, {j.thread} head", f"counterbore for the {j.thread} screw's head"
        return f"access, {j.thread} head", f"access for the {j.thread} screw's head and its driver"
    return "hole", "hole"


def _local(h, pose) -> tuple[np.ndarray, np.ndarray]:
    inv = pose.inverse()
    return inv.apply(np.asarray(h.origin, float)), inv.rotate(np.asarray(h.direction, float))


def _model_holes(asm: Assembly, node: Node) -> list[tuple[np.ndarray, np.ndarray, float, float, tuple[str, str], str]]:
    """Every hole the model cuts in ``node``'s part, in its frame: (origin, direction, diameter, depth,
    (short, long) purpose, joint name)."""
    lay = asm.layout
    nodes = asm.by_part(node.part_id) or [node]
    # the joints' holes of every node of this part, in that node's frame, with what they are for
    known = []
    for j in lay.joints:
        for h in j.holes:
            for n in nodes:
                if h.part == n.name or (h.part == node.part_id and n is nodes[0]):
                    o, d = _local(h, n.pose)
                    known.append((o, d, h, j))
    gland = lay.power.gland
    if node.category == "machined":              # the machined part's own holes are in its frame
        holes = [(np.asarray(h.origin, float), np.asarray(h.direction, float), h) for h in node.spec.holes]
    else:
        case = getattr(node.spec, "spec", None)   # a case half: its spec holds the joints' holes and the gland's
        src = (tuple(h for h in case.holes if h.part == node.part_id) if case is not None and hasattr(case, "holes")
               else lay.holes_for(node.name))
        holes = [(*_local(h, node.pose), h) for h in src]
    out = []
    for o, d, h in holes:
        match = [(float(np.linalg.norm(ko - o)), j, kh) for ko, kd, kh, j in known
                 if abs(kh.diameter - h.diameter) < 1e-6 and abs(kh.depth - h.depth) < 1e-6 and kd @ d > 1 - 1e-6]
        if match:
            _, j, kh = min(match, key=lambda m: m[0])
            purpose, joint = _purpose(asm, j, kh), j.name
        elif node.part_id == "case_lower" and abs(h.diameter - gland.hole_d_mm) < 1e-6:
            pn = asm.rig.part(gland.part_id).part_number
            purpose, joint = ("cable gland", f"cable gland {pn}"), ""
        else:
            purpose, joint = ("hole", "hole"), ""
        out.append((o, d, h.diameter, h.depth, purpose, joint))
    return out


def _feature_purpose(asm: Assembly, node: Node, c: Cylinder) -> tuple[str, str]:
    """What a cylindrical cavity the joints do not cut is for, when the part's spec says (else "hole")."""
    spec, d = node.spec, 2 * c.radius
    names = {n.name for n in asm.by_part(node.part_id)} | {node.name}
    threads = sorted({j.thread for j in asm.layout.joints if any(h.part in names for h in j.holes)})
    thread = threads[0] if len(threads) == 1 else "screw"     # the one thread the part's joints use
    if abs(getattr(spec, "stop_bore", -1.0) - d) < RADIUS_TOL_MM:
        return "lens bore, front stop", "bore for the lens in the front stop"
    if abs(getattr(spec, "access_d", -1.0) - d) < RADIUS_TOL_MM:
        return f"access, {thread} head", f"access for the {thread} screw's head and its driver"
    if abs(getattr(spec, "hole_d", -1.0) - d) < RADIUS_TOL_MM:
        return f"clearance {thread}", f"{thread} clearance"
    case = getattr(spec, "spec", None)
    for cone in getattr(case, "cones", ()):
        if _off_axis(c, cone.apex) < AXIS_TOL_MM:
            return "thermal camera window", "window for a thermal camera"
    for name, (part, pose) in asm.layout.controls.items():   # the panel parts' cut-outs in the case
        if case is not None and _off_axis(c, _local_point(pose.t, node.pose)) < AXIS_TOL_MM:
            return f"cut-out, {part.part_id}", f"cut-out for the {part.part_id}"
    return "hole", "hole"


def _local_point(p, pose) -> np.ndarray:
    return pose.inverse().apply(np.asarray(p, float))


def _face_name(direction) -> str:
    k = int(np.argmax(np.abs(direction)))
    return ("+" if direction[k] < 0 else "-") + "xyz"[k]    # drilled along +z: from the -z face


def holes(asm: Assembly, node: Node, lo: dict[str, tuple[float, float]] | None = None) -> list[HoleMark]:
    """Every hole of ``node``'s part with its position read from the B-rep: each hole the joints (and the
    cable gland) cut, matched to the cylinder of its diameter whose axis runs through it; then every
    other full-circle cylindrical cavity of the solid (a feature of the part: the lens bore, an access
    hole, a window). Positions are ordinates from each view's lower-left corner (``lo`` per view, mm;
    the part's bounding-box corner by default). Ids: one letter per kind of hole (diameter, depth,
    purpose), numbered by position."""
    shape = node.local_shape(asm.cache)
    if lo is None:
        bb = bounds_of(shape)
        lo = {v: (bb.lo[i], bb.lo[k]) for v, (i, k) in VIEW_AXES.items()}
    cyls = [c for c in cylinders(shape) if c.concave]
    tol = hole_position_tolerance(asm, node)
    rows, used = [], set()
    for o, d, dia, depth, (short, long), joint in _model_holes(asm, node):
        k = int(np.argmax(np.abs(d)))
        cand = [(i, c) for i, c in enumerate(cyls) if abs(2 * c.radius - dia) < RADIUS_TOL_MM
                and abs(np.asarray(c.axis) @ d) > 1 - 1e-6 and _off_axis(c, o) < AXIS_TOL_MM]
        if cand:
            i, c = min(cand, key=lambda ic: _off_axis(ic[1], o))
            used.add(i)
            centre = np.asarray(c.point) + (o - np.asarray(c.point)) @ np.asarray(c.axis) * np.asarray(c.axis)
        else:
            centre = o
        rows.append((VIEW_OF_AXIS[k], centre, _face_name(d), dia, depth, short, long, bool(cand), joint))
    for i, c in enumerate(cyls):
        if i in used or c.span_deg < FULL_CIRCLE_DEG or c.extent[1] - c.extent[0] < MIN_DEPTH_MM:
            continue
        a = np.asarray(c.axis)
        k = int(np.argmax(np.abs(a)))
        if abs(a[k]) < 1 - 1e-6:
            continue                             # not along an axis of the part: no view shows it end-on
        short, long = _feature_purpose(asm, node, c)
        centre = np.asarray(c.point) + c.extent[0] * a
        rows.append((VIEW_OF_AXIS[k], centre, "", 2 * c.radius, c.extent[1] - c.extent[0], short, long, True, ""))
    # one letter per kind, in order of diameter; numbered along the view's axes
    kinds = sorted({(round(r[3], 3), round(r[4], 2), r[6]) for r in rows})
    letters = {kd: _letter(n) for n, kd in enumerate(kinds)}
    rows.sort(key=lambda r: (kinds.index((round(r[3], 3), round(r[4], 2), r[6])), r[0],
                             round(r[1][VIEW_AXES[r[0]][0]], 2), round(r[1][VIEW_AXES[r[0]][1]], 2)))
    count: Counter = Counter()
    out = []
    for view, centre, face, dia, depth, short, long, on_solid, joint in rows:
        kd = (round(dia, 3), round(depth, 2), long)
        count[kd] += 1
        i, k = VIEW_AXES[view]
        out.append(HoleMark(f"{letters[kd]}{count[kd]}", view, (float(centre[i] - lo[view][0]), float(centre[k] - lo[view][1])),
                            tuple(float(v) for v in centre), face, float(dia), float(depth), short, long, tol,
                            on_solid, joint))
    return out


def _letter(n: int) -> str:
    s = ""
    n += 1
    while n:
        n, r = divmod(n - 1, 26)
        s = chr(65 + r) + s
    return s


def _hole_groups(marks: list[HoleMark]) -> list[str]:
    """The hole table's summary rows: diameter, depth, count and what they are for, with their ids."""
    groups: dict[tuple, list[str]] = {}
    for m in marks:
        groups.setdefault((round(m.diameter, 3), round(m.depth, 2), m.note), []).append(m.id)
    out = []
    for (d, depth, note), ids in groups.items():
        span = ids[0] if len(ids) == 1 else f"{ids[0]}-{ids[-1]}"
        out.append(f"Ø{round(d, 2):g} x {depth:.1f} deep, {len(ids)} off: {span} ({note})")
    return out


def hole_spacing(asm: Assembly, node: Node, marks: list[HoleMark]) -> tuple[HoleMark, HoleMark] | None:
    """The heat sink's two tapped holes the thermal bar's screws go into (the joints the stack-up's
    "two screws through the bar" feature reads, cad/datums.py): their spacing sets the camera's yaw."""
    if node.category != "machined":
        return None
    pair = [m for m in marks if m.joint.startswith("heat_sink_") and "tap" in m.purpose]
    return (pair[0], pair[1]) if len(pair) == 2 else None


def _extra_rows(asm: Assembly, node: Node, pair: tuple[HoleMark, HoleMark] | None = None,
                lo_z: float = 0.0) -> list[tuple[str, float, str]]:
    """Critical features beyond the outline, for the heat sink: (label, value mm as modelled, tolerance
    text); with the tapped holes' ``pair``, their spacing and the bore's position from them."""
    if node.category != "machined":
        return []
    hs = asm.rig.desc.enclosure.heat_sink
    spec = node.spec
    b, t = spec.body, f"±{hs.tolerance_mm:g}"
    fit = f"+{hs.bore_clearance_mm:g}/0 (the Boson body; thermal contact faces)"
    rows = [("bore width", b.size[1], fit), ("bore height", b.size[2], fit), ("bore length", b.size[0], t),
            (f"fin thickness ({spec.fins} fins a side)", spec.fin_t, t), ("fin height", spec.fin_h, t),
            ("sleeve wall", spec.wall, t), ("base under the sleeve", spec.base, t)]
    if getattr(spec, "stop", 0) > 0:
        rows += [("front stop thickness (datum face)", spec.stop, t), ("front stop bore (the lens)", spec.stop_bore, t)]
    if pair is not None:
        p, q = (np.asarray(m.centre) for m in pair)
        mid = (p + q) / 2
        tp = f"±{pair[0].tolerance:g}"
        ids = f"{pair[0].id}-{pair[1].id}"
        rows += [(f"tapped hole spacing {ids} (sets the yaw)", float(np.linalg.norm((p - q)[:2])), f"{tp} (stack-up)"),
                 (f"bore centre from the {ids} midpoint, x", b.centre[0] - mid[0], tp),
                 (f"bore centre from the {ids} midpoint, y", b.centre[1] - mid[1], tp),
                 ("bore floor above the holes' face (-z)", b.lo[2] - lo_z, t)]
    return rows


#: the hole table's summary rows wrap at this many characters (the table column is ``TABLE_W`` wide)
