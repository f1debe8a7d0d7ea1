"""Dimensioned drawings of the parts a lab makes: every printed part and the machined heat sink, one
SVG each, generated from the model for a machinist or a print service.

Each drawing has three orthographic views of the part in its own frame (third-angle: plan on top,
elevation under it, side view to the right of the elevation), drawn from OpenCascade's hidden-line
removal of the solid at one known scale; overall dimensions on every view with the general tolerance
(``printing.printer.tolerance_mm`` for printed parts, ``enclosure.heat_sink.tolerance_mm`` for the
machined one); a hole table; for the heat sink the bore (the Boson body plus ``bore_clearance_mm``,
the thermal contact), the fins and the base; and a title block (part, material, rig hash, units,
projection).

Holes (:func:`holes`): every hole the joints cut (and the cable gland's), matched to the cylindrical
face of the solid with its diameter whose axis runs through it, plus every other full-circle
cylindrical cavity of the solid (a lens bore, a handle's access hole, a window, a panel part's
cut-out). Each gets an id (a letter per kind: diameter, depth, purpose; numbered by position) drawn
beside a marker on the view that sees it end-on, and a row: its ordinates in mm from that view's
lower-left corner (the datum: the part's lowest coordinates on the two axes of the view), the face it
is drilled from, diameter, depth, position tolerance (the stack-up's "printed/machined hole position"
term, cad/datums.py) and what it is for, from the joint's role for it (insert, tap drill, pilot,
clearance at the screw fit, a head's counterbore or access hole) or the part's spec; otherwise "hole".
A hole the layout lists but the solid does not have is written where the layout puts it and says so.
On the heat sink the two tapped holes the thermal bar's screws go into get their spacing dimensioned
with the stack-up's tolerance (it sets the camera's yaw) and the bore is placed from their midpoint.

Every dimension is a ``<text class="dim">`` with its value in ``data-value`` (mm) and the axis it
measures in ``data-dim``, every hole a ``<text class="hole-pos">`` with ``data-id``, ``data-hole-view``,
``data-at`` (mm), ``data-diameter``, ``data-depth``, ``data-tolerance`` and ``data-for``, so a test (or
a script) reads the numbers back and compares them with the model's measured sizes.
"""
from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import escape

import cadquery as cq
import numpy as np
from OCP.BRepLib import BRepLib
from OCP.GCPnts import GCPnts_QuasiUniformDeflection
from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt
from OCP.HLRAlgo import HLRAlgo_Projector
from OCP.HLRBRep import HLRBRep_Algo, HLRBRep_HLRToShape

from .assembly import Assembly, Node
from .geom import bounds_of

#: the sheet (px); the views are fitted into it at one scale
SHEET_W, SHEET_H = 1400.0, 1000.0
MARGIN, GAP, TABLE_W = 60.0, 90.0, 470.0
#: how far a dimension line stands off the view (px)
DIM_OFFSET = 28.0
#: the curve discretisation of projected edges (mm)
DEFLECTION_MM = 0.05
#: views: name -> (view direction towards the viewer, paper x direction), all in the part's frame
VIEWS = {
    "plan": ((0.0, 0.0, 1.0), (1.0, 0.0, 0.0)),          # paper (x, y)
    "elevation": ((0.0, -1.0, 0.0), (1.0, 0.0, 0.0)),    # paper (x, z)
    "side": ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0)),          # paper (y, z)
}
AXES = {"plan": ("x", "y"), "elevation": ("x", "z"), "side": ("y", "z")}


@dataclass(frozen=True)
class Projection:
    visible: list[list[tuple[float, float]]]   # polylines, mm on the paper
    hidden: list[list[tuple[float, float]]]
    lo: tuple[float, float]
    hi: tuple[float, float]


def project(shape: cq.Shape, direction, xdir) -> Projection:
    """Hidden-line projection of ``shape`` on the plane normal to ``direction``, paper x along ``xdir``."""
    hlr = HLRBRep_Algo()
    hlr.Add(shape.wrapped)
    hlr.Projector(HLRAlgo_Projector(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(*direction), gp_Dir(*xdir))))
    hlr.Update()
    hlr.Hide()
    out = HLRBRep_HLRToShape(hlr)

    def lines(compounds) -> list[list[tuple[float, float]]]:
        res = []
        for c in compounds:
            if c.IsNull():
                continue
            BRepLib.BuildCurves3d_s(c, 1e-4)
            for e in cq.Shape(c).Edges():
                curve = e._geomAdaptor()
                pts = GCPnts_QuasiUniformDeflection(curve, DEFLECTION_MM, curve.FirstParameter(), curve.LastParameter())
                if pts.IsDone() and pts.NbPoints() > 1:
                    res.append([(pts.Value(i + 1).X(), pts.Value(i + 1).Y()) for i in range(pts.NbPoints())])
        return res

    vis = lines([out.VCompound(), out.Rg1LineVCompound(), out.OutLineVCompound()])
    hid = lines([out.HCompound(), out.OutLineHCompound()])
    xs = [p[0] for ln in vis + hid for p in ln]
    ys = [p[1] for ln in vis + hid for p in ln]
    return Projection(vis, hid, (min(xs), min(ys)), (max(xs), max(ys)))


@dataclass(frozen=True)
class Drawing:
    part_id: str
    svg: str
    dims: dict[str, float]        # the overall sizes written on it (mm), by axis


def _tolerance(asm: Assembly, node: Node) -> float:
    d = asm.rig.desc
    return d.enclosure.heat_sink.tolerance_mm if node.category == "machined" else d.printing.printer.tolerance_mm


# ---------------------------------------------------------------------------- holes: what, where, why
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
WRAP_CHARS = 76


def _wrap(text: str, width: int) -> list[str]:
    out, line = [], ""
    for word in text.split(" "):
        if line and len(line) + 1 + len(word) > width:
            out.append(line)
            line = word
        else:
            line = f"{line} {word}" if line else word
    return out + [line]


def _fmt(v: float) -> str:
    return f"{v:.2f}"


def drawing(asm: Assembly, node: Node) -> Drawing:
    """The dimensioned drawing of ``node``'s part (in its own frame)."""
    shape = node.local_shape(asm.cache)
    bb = bounds_of(shape)
    size = dict(zip("xyz", bb.size))
    tol = _tolerance(asm, node)
    proj = {v: project(shape, d, x) for v, (d, x) in VIEWS.items()}
    # the holes, their ordinates from each view's lower-left corner (the drawn outline's: the datum)
    marks = holes(asm, node, lo={v: p.lo for v, p in proj.items()})
    pair = hole_spacing(asm, node, marks)
    # one scale: plan over elevation (width x), side beside the elevation (width y); heights y and z
    w = size["x"] + size["y"]
    h = size["y"] + size["z"]
    s = min((SHEET_W - 2 * MARGIN - GAP - TABLE_W) / w, (SHEET_H - 2 * MARGIN - GAP - 60) / h)
    origin = {"plan": (MARGIN, MARGIN), "elevation": (MARGIN, MARGIN + size["y"] * s + GAP),
              "side": (MARGIN + size["x"] * s + GAP, MARGIN + size["y"] * s + GAP)}
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{SHEET_W:g}" height="{SHEET_H:g}" '
           f'viewBox="0 0 {SHEET_W:g} {SHEET_H:g}" data-part="{node.part_id}" data-scale-px-per-mm="{s:.6f}">',
           '<style>.v{fill:none;stroke:#000;stroke-width:1}.h{fill:none;stroke:#999;stroke-width:0.6;'
           'stroke-dasharray:4 3}.d{stroke:#1f4e9c;stroke-width:0.7}text{font-family:sans-serif;font-size:13px}'
           '.dim{fill:#1f4e9c}.hm{fill:none;stroke:#c0392b;stroke-width:0.8}'
           '.hole-id{font-size:10px;fill:#c0392b;paint-order:stroke;stroke:#fff;stroke-width:3px;stroke-linejoin:round}'
           '.datum{fill:#1f4e9c;font-size:10px}.pos{font-size:10px}.pos-head{font-size:10px;font-weight:bold}</style>',
           f'<rect x="1" y="1" width="{SHEET_W - 2:g}" height="{SHEET_H - 2:g}" fill="#fff" stroke="#000"/>']
    for view, p in proj.items():
        ox, oy = origin[view]
        ax, ay = AXES[view]
        vh = (p.hi[1] - p.lo[1]) * s

        def tx(pt, p=p, ox=ox, oy=oy, vh=vh):     # paper mm -> sheet px (y up on paper, down on the sheet)
            return ox + (pt[0] - p.lo[0]) * s, oy + vh - (pt[1] - p.lo[1]) * s

        out.append(f'<g class="view" id="view-{view}" data-width-mm="{p.hi[0] - p.lo[0]:.4f}" '
                   f'data-height-mm="{p.hi[1] - p.lo[1]:.4f}">')
        for cls, lines in (("h", p.hidden), ("v", p.visible)):
            for ln in lines:
                pts = " ".join(f"{a:.2f},{b:.2f}" for a, b in map(tx, ln))
                out.append(f'<polyline class="{cls}" points="{pts}"/>')
        out.append(f'<text x="{ox:g}" y="{oy - 8:g}">{view} ({ax}, {ay})</text>')
        # overall dimensions: the width under the view, the height to its left
        wmm, hmm = p.hi[0] - p.lo[0], p.hi[1] - p.lo[1]
        y_d = oy + vh + DIM_OFFSET
        out.append(f'<line class="d" x1="{ox:.2f}" y1="{y_d:.2f}" x2="{ox + wmm * s:.2f}" y2="{y_d:.2f}"/>')
        out.append(f'<text class="dim" data-view="{view}" data-dim="{ax}" data-value="{wmm:.3f}" '
                   f'x="{ox + wmm * s / 2:.2f}" y="{y_d - 4:.2f}" text-anchor="middle">{wmm:.1f} ±{tol:g}</text>')
        x_d = ox - DIM_OFFSET
        out.append(f'<line class="d" x1="{x_d:.2f}" y1="{oy:.2f}" x2="{x_d:.2f}" y2="{oy + vh:.2f}"/>')
        out.append(f'<text class="dim" data-view="{view}" data-dim="{ay}" data-value="{hmm:.3f}" '
                   f'x="{x_d - 4:.2f}" y="{oy + vh / 2:.2f}" text-anchor="middle" '
                   f'transform="rotate(-90 {x_d - 4:.2f} {oy + vh / 2:.2f})">{hmm:.1f} ±{tol:g}</text>')
        out.append("</g>")
        mine = [m for m in marks if m.view == view]
        if not mine:
            continue
        # the datum: the view's lower-left corner, every hole's ordinates run from it
        out.append(f'<g class="holes" id="holes-{view}">')
        out.append(f'<path class="d" d="M{ox:.2f},{oy + vh + 6:.2f} L{ox:.2f},{oy + vh:.2f} L{ox - 6:.2f},{oy + vh:.2f}"/>')
        out.append(f'<text class="datum" x="{ox + 3:.2f}" y="{oy + vh + 12:.2f}">0,0 ({ax}, {ay})</text>')
        at: dict[tuple[int, int], list[str]] = {}
        for m in mine:
            cx, cy = tx((p.lo[0] + m.at[0], p.lo[1] + m.at[1]))
            r = max(m.diameter / 2 * s, 2.0)
            out.append(f'<circle class="hm" data-hole="{m.id}" cx="{cx:.2f}" cy="{cy:.2f}" r="{r:.2f}"/>')
            out.append(f'<path class="hm" d="M{cx - r - 2:.2f},{cy:.2f} H{cx + r + 2:.2f} M{cx:.2f},{cy - r - 2:.2f} '
                       f'V{cy + r + 2:.2f}"/>')
            at.setdefault((round(cx), round(cy)), []).append(m.id)
        for (cx, cy), ids in at.items():
            r = max(max(m.diameter for m in mine if m.id in ids) / 2 * s, 2.0)
            out.append(f'<text class="hole-id" data-ids="{" ".join(ids)}" x="{cx + 0.7 * r + 2:.1f}" '
                       f'y="{cy - 0.7 * r - 2:.1f}">{"/".join(ids)}</text>')
        if pair is not None and pair[0].view == view:
            out.append(_spacing_dim(pair, tx, p, ox, oy, wmm * s, vh))
        out.append("</g>")
    # the table: title block, critical features, holes (kinds, then each hole's position)
    tx0, ty = SHEET_W - MARGIN - TABLE_W + 20, MARGIN
    material = asm.rig.desc.enclosure.heat_sink.material if node.category == "machined" else asm.rig.desc.printing.printer.material
    rows = [f"<tspan font-weight='bold'>{escape(node.part_id)}</tspan>", f"{node.category}, {escape(material)}",
            f"units mm; general tolerance ±{tol:g}", "third-angle projection", f"rig {asm.rig.hash[:12]}",
            f"quantity per rig {len(asm.by_part(node.part_id))}"]
    for r in rows:
        out.append(f'<text x="{tx0:g}" y="{ty:g}">{r}</text>')
        ty += 20
    extra = _extra_rows(asm, node, pair, bb.lo[2])
    if extra:
        ty += 10
        out.append(f'<text x="{tx0:g}" y="{ty:g}" font-weight="bold">critical features</text>')
        for k, (label, v, t) in enumerate(extra):
            ty += 17
            out.append(f'<text class="dim" data-dim="feature-{k}" data-label="{escape(label)}" data-value="{v:.3f}" '
                       f'x="{tx0:g}" y="{ty:g}" font-size="11">{escape(label)}: {_fmt(v)} {escape(t)}</text>')
    if marks:
        ty += 26
        out.append(f'<text x="{tx0:g}" y="{ty:g}" font-weight="bold">holes</text>')
        for r in _hole_groups(marks):
            lines = _wrap(r, WRAP_CHARS)
            ty += 15
            spans = "".join(f'<tspan x="{tx0 + (12 if k else 0):g}" dy="{13 if k else 0}">{escape(ln)}</tspan>'
                            for k, ln in enumerate(lines))
            out.append(f'<text class="hole" x="{tx0:g}" y="{ty:g}" font-size="10">{spans}</text>')
            ty += 13 * (len(lines) - 1)
        # one row a hole: id, the view and face, its ordinates from the view's datum corner, size, tolerance, use
        step = min(13.0, (SHEET_H - 20 - ty - 40) / (len(marks) + 1))
        ty += 20
        out.append(f'<text class="pos" x="{tx0:g}" y="{ty:g}">positions: mm from each view\'s datum corner (0,0: '
                   f'the part\'s lowest x, y, z)</text>')
        ty += step + 2
        out.append(_pos_row(tx0, ty, ("id", "view", "from", "at", "", "Ø", "depth", "pos.", "for"), head=True))
        for m in marks:
            ty += step
            a1, a2 = AXES[m.view]
            cells = (m.id, m.view, m.face or "-", f"{a1} {_fmt(m.at[0])}", f"{a2} {_fmt(m.at[1])}", f"{m.diameter:.2f}",
                     f"{m.depth:.1f}", f"±{m.tolerance:g}", m.purpose + ("" if m.on_solid else " (layout; not on the solid)"))
            attrs = (f'data-id="{m.id}" data-hole-view="{m.view}" data-axes="{a1}{a2}" '
                     f'data-at="{m.at[0]:.4f} {m.at[1]:.4f}" data-centre="{" ".join(f"{v:.4f}" for v in m.centre)}" '
                     f'data-diameter="{m.diameter:.4f}" data-depth="{m.depth:.4f}" data-tolerance="{m.tolerance:g}" '
                     f'data-face="{m.face}" data-for="{escape(m.purpose)}" data-on-solid="{int(m.on_solid)}"')
            out.append(_pos_row(tx0, ty, cells, attrs=attrs, size=min(10.0, step - 1)))
    out.append("</svg>")
    return Drawing(node.part_id, "\n".join(out) + "\n", {k: round(v, 3) for k, v in size.items()})


#: the position table's columns (px from the table's left edge)
POS_COLUMNS = (0, 30, 88, 120, 182, 244, 286, 320, 356)


def _pos_row(x0: float, y: float, cells, *, head: bool = False, attrs: str = "", size: float = 10.0) -> str:
    spans = "".join(f'<tspan x="{x0 + c:g}">{escape(str(v))}</tspan>' for c, v in zip(POS_COLUMNS, cells))
    cls = "pos-head" if head else "hole-pos"
    return f'<text class="{cls}" {attrs} y="{y:.1f}" font-size="{size:.1f}">{spans}</text>'


def _spacing_dim(pair: tuple[HoleMark, HoleMark], tx, p: Projection, ox: float, oy: float, w_px: float, h_px: float) -> str:
    """The two tapped holes' spacing as a dimension beside the view, with its tolerance (a ``dim`` text)."""
    a, b = (tx((p.lo[0] + m.at[0], p.lo[1] + m.at[1])) for m in pair)
    d = math.hypot(pair[0].at[0] - pair[1].at[0], pair[0].at[1] - pair[1].at[1])
    label = f"{d:.2f} ±{pair[0].tolerance:g} ({pair[0].id}-{pair[1].id})"
    attrs = (f'class="dim" data-dim="hole-spacing" data-holes="{pair[0].id} {pair[1].id}" data-value="{d:.4f}" '
             f'data-tolerance="{pair[0].tolerance:g}"')
    parts = []
    if abs(a[1] - b[1]) >= abs(a[0] - b[0]):       # apart on the sheet's vertical: dimension to the right
        xd = ox + w_px + 18
        for x, y in (a, b):
            parts.append(f'<line class="d" x1="{x:.2f}" y1="{y:.2f}" x2="{xd + 4:.2f}" y2="{y:.2f}"/>')
        parts.append(f'<line class="d" x1="{xd:.2f}" y1="{a[1]:.2f}" x2="{xd:.2f}" y2="{b[1]:.2f}"/>')
        ym = (a[1] + b[1]) / 2
        parts.append(f'<text {attrs} x="{xd + 14:.2f}" y="{ym:.2f}" text-anchor="middle" '
                     f'transform="rotate(-90 {xd + 14:.2f} {ym:.2f})">{label}</text>')
    else:                                            # apart across: dimension above the view
        yd = oy - 22
        for x, y in (a, b):
            parts.append(f'<line class="d" x1="{x:.2f}" y1="{y:.2f}" x2="{x:.2f}" y2="{yd - 4:.2f}"/>')
        parts.append(f'<line class="d" x1="{a[0]:.2f}" y1="{yd:.2f}" x2="{b[0]:.2f}" y2="{yd:.2f}"/>')
        parts.append(f'<text {attrs} x="{(a[0] + b[0]) / 2:.2f}" y="{yd - 4:.2f}" text-anchor="middle">{label}</text>')
    return "\n".join(parts)


def write_drawings(asm: Assembly, folder: Path) -> list[Path]:
    """``<part>.drawing.svg`` for every printed and machined part, into ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    out = []
    for pid, n in asm.printed().items():
        p = folder / f"{pid}.drawing.svg"
        p.write_text(drawing(asm, n).svg)
        out.append(p)
    return out


def scale_of(svg_text: str) -> float:
    import re
    m = re.search(r'data-scale-px-per-mm="([0-9.]+)"', svg_text)
    return float(m.group(1)) if m else math.nan
