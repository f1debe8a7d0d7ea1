"""`cad/build.py check`: every check of the assembly, each returning a :class:`CheckResult` with a
readable detail. A failed check makes the command exit 1.

Interference is measured, not assumed: every pair of parts whose boxes overlap is intersected, and the
overlap volume is compared with what the joint that placed them intends (an insert melts
``melt_volume`` of plastic; a screw's thread fills its tapped hole). An intended overlap that measures
more than intended fails too, so a real clash cannot hide behind the allow-list.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import cadquery as cq
import numpy as np
from OCP.BRepExtrema import BRepExtrema_DistShapeShape

from platform_tools.rig.progress import progress

from .assembly import PRINT_SETUPS, Assembly, Node
from .layout import fov_half_angles_deg
from .geom import Bounds
from .solids import TOUCH_MM3, bounds_of, box, common_volume_mm3
from .parts.common import on_bed
from cad.bought.fasteners import fastener_table

TOL_REL, TOL_ABS = 0.05, 0.5
DATUM_CONTACT_MM = 0.02  # a datum contact further than this from its part's surface is not in the geometry


@dataclass
class CheckResult:
    name: str
    ok: bool
    summary: str
    details: list[str] = field(default_factory=list)
    data: dict = field(default_factory=dict)


def _bounds(asm: Assembly, n: Node) -> Bounds:
    return bounds_of(n.shape(asm.cache))


def check_valid(asm: Assembly) -> CheckResult:
    bad = []
    for n in asm.nodes:
        s = n.shape(asm.cache)
        if not s.isValid() or s.Volume() <= 0 or len(s.Solids()) != 1:
            bad.append(f"{n.name} ({n.part_id}): valid={s.isValid()} volume={s.Volume():.2f} solids={len(s.Solids())}")
    return CheckResult("valid solids", not bad, f"{len(asm.nodes) - len(bad)}/{len(asm.nodes)} parts are one valid solid", bad)


def intended_overlaps(asm: Assembly) -> dict[frozenset, tuple[float, str]]:
    """Overlaps the design means, by node pair: (expected volume mm^3, why)."""
    out: dict[frozenset, tuple[float, str]] = {}
    rig = asm.rig
    ins = asm.layout.fits.insert
    for j in asm.layout.joints:
        screw = f"screw_{j.name}"
        d = j.diameter_mm
        if j.kind == "insert":
            out[frozenset((f"insert_{j.name}", j.host))] = (ins.melt_volume_mm3(), "heat-set insert melted into its hole")
            out[frozenset((screw, f"insert_{j.name}"))] = (0.0, "screw in its insert")
        elif j.kind == "tapped":
            tap = fastener_table().size(j.thread).tap_drill_mm if j.host.startswith("heat_sink") else 0.0
            out[frozenset((screw, j.host))] = (math.pi / 4 * (d * d - tap * tap) * j.engagement_mm,
                                               f"thread engaged {j.engagement_mm:.1f} mm in a tapped hole")
        else:
            pilot = rig.dim(j.screw_id, "pilot_hole_diameter_mm")
            out[frozenset((screw, j.host))] = (math.pi / 4 * (d * d - pilot * pilot) * j.engagement_mm,
                                               "self-tapping thread cut into the plastic")
    for n in asm.nodes:
        if n.props.get("kind") == "standoff":
            out[frozenset((n.name, n.props["host"]))] = (n.spec.stud_volume_mm3(),
                                                          f"standoff's {n.spec.stud_mm:g} mm stud in the devkit's thread")
    return out


def check_interference(asm: Assembly) -> CheckResult:
    nodes = asm.nodes
    boxes = {n.name: _bounds(asm, n) for n in nodes}
    intended = intended_overlaps(asm)
    pairs = [(a, b) for i, a in enumerate(nodes) for b in nodes[i + 1:] if boxes[a.name].overlaps(boxes[b.name], 1e-6)]
    clashes, allowed, seen = [], [], set()
    for a, b in progress(pairs, desc="interference"):
        key = frozenset((a.name, b.name))
        v = common_volume_mm3(a.shape(asm.cache), b.shape(asm.cache))
        if key in intended:
            exp, why = intended[key]
            seen.add(key)
            ok = abs(v - exp) <= max(TOL_ABS, TOL_REL * exp)
            allowed.append(f"{a.name} / {b.name}: {v:.2f} mm^3 (intended {exp:.2f}: {why})" + ("" if ok else "  <-- MISMATCH"))
            if not ok:
                clashes.append(f"{a.name} / {b.name}: intended overlap measures {v:.2f} mm^3, expected {exp:.2f} ({why})")
        elif v > TOUCH_MM3:
            clashes.append(f"{a.name} ({a.part_id}) / {b.name} ({b.part_id}): {v:.2f} mm^3 overlap")
    missing = [f"{'/'.join(sorted(k))}: intended overlap not found (the parts do not meet)" for k in intended
               if k not in seen and intended[k][0] > 0]
    problems = clashes + missing
    return CheckResult("interference", not problems,
                       f"{len(pairs)} pairs with touching boxes; {len(clashes)} clashes; "
                       f"{len(allowed)} intended overlaps measured", problems + ["intended:"] + allowed[:400],
                       dict(pairs=len(pairs)))


def min_wall_of(shape: cq.Shape, samples: int | None = None, where: list | None = None, **kw) -> float:
    """Thinnest material of ``shape`` (cad/walls.py: face grids, edges, adaptive refinement)."""
    from .walls import min_wall_of as measure
    return measure(shape, samples, where, **kw)


def check_min_wall(asm: Assembly) -> CheckResult:
    """Every printed part's thinnest wall (cad/walls.py) against the printer's minimum wall. Near an
    edge the wall is read half a nozzle inside the face, where the slicer's outer perimeter runs."""
    from .walls import thin_places
    p = asm.rig.desc.printing.printer
    need = p.nozzle_mm * p.min_wall_nozzles
    details, bad, data = [], [], {}
    for pid, n in asm.printed().items():
        if n.category != "printed":
            continue
        best, places = thin_places(n.local_shape(asm.cache), below=need - 1e-3, edge_inset=p.nozzle_mm / 2)
        data[pid] = dict(thinnest_mm=round(best.thickness, 2) if best else None, point=best.point if best else None,
                         feature=best.feature if best else None, thin=[(round(w.thickness, 2), w.point) for w in places])
        details.append(f"{pid}: thinnest wall {best.line() if best else 'none found'} (part frame)")
        bad += [f"{pid}: {w.line()} < {need:g} mm (part frame)" for w in places]
    return CheckResult("minimum wall", not bad, f"every printed wall >= {need:g} mm ({p.min_wall_nozzles:g} x {p.nozzle_mm:g} mm nozzle)"
                       if not bad else f"{len(bad)} places in {len({b.split(':')[0] for b in bad})} parts have walls under {need:g} mm",
                       bad + details, data)


def distance(a: cq.Shape, b: cq.Shape) -> float:
    d = BRepExtrema_DistShapeShape(a.wrapped, b.wrapped)
    d.Perform()
    return d.Value()


def check_clearances(asm: Assembly) -> CheckResult:
    gap = asm.rig.desc.enclosure.heat_sink_gap_mm
    sh = lambda name: asm.node(name).shape(asm.cache)
    walls = ["case_lower", "case_lid"]
    pairs = [("heat_sink_left", "heat_sink_right")]
    for side in ("left", "right"):
        pairs += [(f"heat_sink_{side}", w) for w in walls] + [(f"fan_{side}", w) for w in walls]
        pairs += [(f"heat_sink_{side}", f"fan_{o}") for o in ("left", "right")]
    details, bad = [], []
    for a, b in pairs:
        d = distance(sh(a), sh(b))
        line = f"{a} to {b}: {d:.2f} mm"
        details.append(line)
        if d < gap - 1e-6:
            bad.append(line + f" < {gap:g} mm (enclosure.heat_sink_gap_mm)")
    return CheckResult("heat sink / fan / wall clearances", not bad, f"all >= {gap:g} mm" if not bad else "too close",
                       bad + details)


def check_bed(asm: Assembly) -> CheckResult:
    bed = asm.rig.desc.printing.printer.bed_mm
    details, bad = [], []
    for pid, n in asm.printed().items():
        if n.category != "printed":
            continue
        s, _ = on_bed(n.local_shape(asm.cache), PRINT_SETUPS[pid], bed)
        bb = s.BoundingBox()
        size = (bb.xlen, bb.ylen, bb.zlen)
        fits = all(a <= b + 1e-6 for a, b in zip(size, bed))
        line = f"{pid}: {size[0]:.1f} x {size[1]:.1f} x {size[2]:.1f} mm in its print orientation"
        details.append(line)
        if not fits:
            bad.append(line + f" > bed {bed[0]:g} x {bed[1]:g} x {bed[2]:g}")
    return CheckResult("print bed", not bad, "every printed part fits the bed" if not bad else "parts exceed the bed",
                       bad + details)


def frustum(apex: np.ndarray, R: np.ndarray, half_h: float, half_v: float, near: float, far: float) -> cq.Shape:
    """A view frustum from ``near`` to ``far`` along the optical z axis (optical frame R columns)."""
    def rect(dist):
        hx, hy = dist * math.tan(math.radians(half_h)), dist * math.tan(math.radians(half_v))
        pts = [apex + R @ np.array([sx * hx, sy * hy, dist]) for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
        return cq.Wire.makePolygon([cq.Vector(*p) for p in pts], close=True)
    return cq.Solid.makeLoft([rect(near), rect(far)], True)


def camera_frusta(asm: Assembly) -> dict[str, tuple[cq.Shape, list[str]]]:
    """Each camera's frustum and the nodes that belong to that camera (excluded from its test)."""
    from .assembly import camera_frames
    lay = asm.layout
    halves = fov_half_angles_deg(lay.rig)
    frames = camera_frames(asm)
    out = {}
    for name, T in frames.items():
        if name.startswith("zed"):
            hh, hv = halves["zed_x"]
            near = lay.cameras.zed.front_mm + 0.05
            own = ["zed_x"]
        else:
            hh, hv = halves["thermal"]
            near = lay.cameras.lens.front_mm + 0.05
            side = name.split("_")[1]
            own = [f"boson_{side}", f"boson_lens_{side}"]
            # a fisheye sees a cone: its diagonal half angle all round holds the whole image
            r0, r1 = near * math.tan(math.radians(hh)), lay.c.fov_length_mm * math.tan(math.radians(hh))
            axis = T.R[:, 2]
            out[name] = (cq.Solid.makeCone(r0, r1, lay.c.fov_length_mm - near, cq.Vector(*(T.t + near * axis)),
                                           cq.Vector(*axis)), own)
            continue
        out[name] = (frustum(T.t, T.R, hh, hv, near, lay.c.fov_length_mm), own)
    return out


def check_fov(asm: Assembly, extra: list[tuple[str, cq.Shape]] = ()) -> CheckResult:
    details, bad = [], []
    for cam, (fr, own) in camera_frusta(asm).items():
        fb = bounds_of(fr)
        hits = []
        items = [(n.name, n.shape(asm.cache)) for n in asm.nodes if n.name not in own] + list(extra)
        for name, s in items:
            if not bounds_of(s).overlaps(fb):
                continue
            v = common_volume_mm3(s, fr)
            if v > TOUCH_MM3:
                hits.append(f"{name} ({v:.1f} mm^3)")
        details.append(f"{cam}: " + (", ".join(hits) if hits else "clear"))
        if hits:
            bad.append(f"{cam}'s field of view is obstructed by " + ", ".join(hits))
    h = fov_half_angles_deg(asm.rig)
    return CheckResult("fields of view", not bad,
                       f"ZED X {2 * h['zed_x'][0]:.0f} x {2 * h['zed_x'][1]:.0f} deg and Boson {2 * h['thermal'][0]:.0f} deg "
                       f"(diagonal) frusta to {asm.layout.c.fov_length_mm:g} mm are clear" if not bad else "obstructed",
                       bad + details)


def check_battery(asm: Assembly, extra: list[tuple[str, cq.Shape]] = ()) -> CheckResult:
    lay = asm.layout
    bat = asm.node("makita_battery")
    b = _bounds(asm, bat)
    travel = lay.power.battery.size[0] + 5.0
    d = np.asarray(lay.power.battery.slide_direction)
    lo = np.minimum(np.array(b.lo), np.array(b.lo) + d * travel)
    hi = np.maximum(np.array(b.hi), np.array(b.hi) + d * travel)
    sweep = box(Bounds(tuple(lo + 0.01), tuple(hi - 0.01)))
    hits = []
    items = [(n.name, n.shape(asm.cache)) for n in asm.nodes if n.name not in ("makita_battery", "makita_adapter")]
    for name, s in items + list(extra):
        if not bounds_of(s).overlaps(bounds_of(sweep)):
            continue
        v = common_volume_mm3(s, sweep)
        if v > TOUCH_MM3:
            hits.append(f"{name} ({v:.1f} mm^3)")
    return CheckResult("battery slides out", not hits,
                       f"the battery's {travel:.0f} mm path along {tuple(d)} is clear" if not hits else
                       "the battery's path is blocked by " + ", ".join(hits), hits)


def check_vents(asm: Assembly) -> CheckResult:
    lay = asm.layout
    shell = box(lay.case.outer).cut(box(lay.case.interior))
    area = 0.0
    for v in lay.case.vents:
        area += common_volume_mm3(shell, box(v)) / lay.fits.wall
    fans = 2 * lay.cooling.part.inlet_area_mm2
    ratio = lay.rig.desc.enclosure.vents.min_area_ratio
    ok = area >= fans * ratio
    return CheckResult("vent area", ok, f"{len(lay.case.vents)} slots, {area:.0f} mm^2 open; fan inlets {fans:.0f} mm^2 x "
                       f"{ratio:g} = {fans * ratio:.0f} mm^2 needed", [] if ok else
                       ["enclosure.vents: add slots or make them longer"], dict(area_mm2=area, needed_mm2=fans * ratio))


def mass_properties(asm: Assembly) -> dict:
    rig = asm.rig
    total, moment = 0.0, np.zeros(3)
    rows = []
    for n in asm.nodes:
        s = n.shape(asm.cache)
        com = np.array(cq.Shape.centerOfMass(s).toTuple())
        if n.category == "printed":
            m = s.Volume() / 1000 * rig.desc.printing.printer.density_g_cm3
        elif n.category == "machined":
            m = s.Volume() / 1000 * rig.desc.enclosure.heat_sink.density_g_cm3
        else:
            m = rig.part(n.part_id).mass_g.value
        rows.append((n.name, m))
        total += m
        moment += m * com
    com = moment / total
    return dict(mass_g=total, com_mm=com.tolist(), heaviest=sorted(rows, key=lambda r: -r[1])[:5])


def check_mass(asm: Assembly) -> CheckResult:
    mp = mass_properties(asm)
    com = np.array(mp["com_mm"])
    g = asm.layout.handles.geometry
    details = [f"total {mp['mass_g'] / 1000:.2f} kg; centre of mass at x {com[0]:.1f}, y {com[1]:.1f}, z {com[2]:.1f} mm (rig frame)"]
    bad = []
    for name, pose in asm.layout.handles.poses.items():
        grip = pose.apply(np.array([0.0, 0.0, g.post_height + g.grip_d / 2]))
        axis = pose.rotate(np.array([1.0, 0, 0]))
        rel = com - grip
        along = float(rel @ axis)
        details.append(f"handle_{name}: grip centre at ({grip[0]:.1f}, {grip[1]:.1f}, {grip[2]:.1f}); centre of mass "
                       f"{along:+.1f} mm along the grip, {np.linalg.norm(rel - along * axis):.1f} mm from its axis")
        if name == "top" and abs(along) > g.grip_length / 2:
            bad.append(f"the centre of mass is {abs(along):.0f} mm along the top grip, beyond its "
                       f"{g.grip_length / 2:.0f} mm half length: the rig tips when carried")
    details += [f"heaviest: {n} {m:.0f} g" for n, m in mp["heaviest"]]
    return CheckResult("mass and balance", not bad, f"{mp['mass_g'] / 1000:.2f} kg, centre of mass under the top grip"
                       if not bad else "unbalanced", bad + details, mp)


def check_estimates(asm: Assembly) -> CheckResult:
    est = asm.rig.estimates()
    return CheckResult("estimates (information)", True, f"{len(est)} dimensions are estimates: measure real parts",
                       [f"{e.path} = {e.value:g}" + (f" ({e.note})" if e.note else "") for e in est])


def printed_meshes(asm: Assembly, tolerance: float = 0.1, angular: float = 0.2) -> dict[str, np.ndarray]:
    """Every printed part in its print orientation as the STL triangles an export writes, read back
    from the file (the mesh a slicer gets, not the B-rep)."""
    import tempfile
    from pathlib import Path
    from .printability import read_stl
    bed = asm.rig.desc.printing.printer.bed_mm
    out = {}
    with tempfile.TemporaryDirectory(prefix="rig-printable-") as tmp:
        for pid, n in asm.printed().items():
            if n.category != "printed" or pid not in PRINT_SETUPS:
                continue
            shape, _ = on_bed(n.local_shape(asm.cache), PRINT_SETUPS[pid], bed)
            path = Path(tmp) / f"{pid}.stl"
            cq.exporters.export(shape, str(path), "STL", tolerance=tolerance, angularTolerance=angular)
            out[pid] = read_stl(path)
    return out


def printability_of(asm: Assembly, meshes: dict[str, np.ndarray] | None = None) -> dict:
    """Part id -> :class:`cad.printability.Printability` of every printed part's exported mesh in its print
    orientation (``meshes``: :func:`printed_meshes` unless given), at the rig printer's limits."""
    from .printability import analyse
    p = asm.rig.desc.printing.printer
    meshes = printed_meshes(asm) if meshes is None else meshes
    return {pid: analyse(tri, p.max_overhang_deg, p.max_bridge_mm) for pid, tri in meshes.items()}


def check_printable(asm: Assembly, meshes: dict[str, np.ndarray] | None = None) -> CheckResult:
    """No support needed: on every printed part's exported mesh, in its print orientation, every face
    overhanging more than ``max_overhang_deg`` is a bridge from supported edges of at most
    ``max_bridge_mm`` (cad/printability.py says how that is measured)."""
    p = asm.rig.desc.printing.printer
    results = printability_of(asm, meshes)
    details, bad, data = [], 0, {}
    for pid, r in results.items():
        data[pid] = dict(bed_contact_mm2=r.bed_contact_mm2, overhang_mm2=r.overhang_mm2,
                         failing=[g.describe() for g in r.failing])
        details.append(f"{pid}: {'ok' if r.ok else 'NEEDS SUPPORT'}; on the bed {r.bed_contact_mm2:.0f} mm^2, "
                       f"{len(r.regions)} overhanging patches ({r.overhang_mm2:.0f} mm^2), longest bridge "
                       f"{r.longest_bridge_mm:.1f} mm")
        for g in r.failing:
            bad += 1
            details.append(f"  {pid}: {g.describe()}")
    return CheckResult("printable without supports", bad == 0,
                       f"{len(results)} printed parts, {bad} patches overhanging more than {p.max_overhang_deg:g} deg "
                       f"or bridging more than {p.max_bridge_mm:g} mm", details, data)


def check_assembly_order(asm: Assembly, steps=None, extra=()) -> CheckResult:
    """Every screw has a straight driver path at the guide's step that fits it (cad/assembly_order.py)."""
    from .assembly_order import driver_paths
    r = driver_paths(asm, steps, extra)
    blocked = len({p.split(" ")[0] for p in r.problems})
    return CheckResult("assembly order", not r.problems,
                       f"{r.screws} screws, each driven at its step clear of every part installed by then"
                       if not r.problems else f"{blocked} of {r.screws} screws cannot be driven at their step",
                       r.problems + r.details, r.data)


def check_electrical(asm: Assembly) -> CheckResult:
    """Power path and sync trigger (cad.electrical): switch, fuse and converter ratings against the current
    computed from the placed parts' power, the trigger level against the Boson's sync input, the LED's voltage."""
    from .electrical import electrical_checks, power_counts
    res = electrical_checks(asm.rig, power_counts(asm))
    bad = [f"{r.name}: {r.text}" for r in res if not r.ok]
    return CheckResult("electrical", not bad, "switch, fuse, converter, sync level and LED fit the power budget"
                       if not bad else f"{len(bad)} electrical problem(s)", bad + [f"{r.name}: {r.text}" for r in res if r.ok])


def check_power_parts(asm: Assembly, extra=()) -> CheckResult:
    """The gland's hole and locknut socket path, the breakouts' plug room, the cut-off on its bosses
    (cad/passthrough.py)."""
    from .passthrough import power_part_problems
    bad, details, data = power_part_problems(asm, list(extra))
    return CheckResult("power and sync parts", not bad, "gland hole as its table, locknut and plugs reachable"
                       if not bad else f"{len(bad)} problem(s) fitting the gland, cut-off or breakouts",
                       bad + details, data)


def check_datums(asm: Assembly, locations=None) -> CheckResult:
    """Every camera located by named features (cad/datums.py): each location of its chain removes all six
    degrees of freedom, each feature exactly the ones it claims, and every contact lies on the built
    geometry of the part that carries it (and of the part it locates, for a face both touch)."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
    from OCP.gp import gp_Pnt
    from .datums import camera_locations, contact_gaps, datum_problems
    from .tolerances import stack_up
    locations = camera_locations(asm.layout) if locations is None else locations
    bad, details = datum_problems(locations)

    def gap(node: str, p) -> float:
        v = cq.Shape.cast(BRepBuilderAPI_MakeVertex(gp_Pnt(*p)).Vertex())
        return distance(asm.node(node).shape(asm.cache), v)
    for cam, feature, node, g in contact_gaps(locations, gap):
        if g > DATUM_CONTACT_MM:
            bad.append(f"{cam}: {feature}: its contact is {g:.2f} mm off {node}: the feature is not in the geometry")
    data = {}
    for cam in locations:
        u = stack_up(locations, cam, "zed_x" if cam != "zed_x" else None)
        data[cam] = u.as_dict()
        details.append(f"{cam} ({'relative to the ZED X' if cam != 'zed_x' else 'in the case'}): worst case "
                       + ", ".join(f"{n} {v:.2f}" for n, v in zip(("x", "y", "z"), u.worst[:3])) + " mm, "
                       + ", ".join(f"{n} {v:.2f}" for n, v in zip(("roll", "pitch", "yaw"), u.worst[3:])) + " deg; 1 sigma "
                       + " / ".join(f"{v:.2f}" for v in u.sigma) + " (mm, deg)")
    n = sum(len(f.contacts) for chain in locations.values() for loc in chain for f in loc.features)
    return CheckResult("camera datums", not bad, f"{len(locations)} cameras, {sum(len(c) for c in locations.values())} "
                       f"locations, {n} contacts: each held in 6 DOF by named features on the geometry"
                       if not bad else f"{len(bad)} datum problem(s)", bad + details, data)


def check_cables(asm: Assembly, extra_routes=(), only=None) -> CheckResult:
    """The key cables swept along their routes: bend radius, interference, length (cad/cables.py)."""
    from .cables import cable_report
    r = cable_report(asm, list(extra_routes), only)
    return CheckResult("cables", not r.problems, f"{len(r.paths)} cables routed, bends and paths clear"
                       if not r.problems else f"{len(r.problems)} cable problem(s)", r.problems + r.details,
                       dict(lengths={p.route.name: round(p.length_mm, 1) for p in r.paths}))


def check_grip_span(asm: Assembly) -> CheckResult:
    """The clear span between each handle's posts (cad/ergonomics.py) against the rig's ergonomic minimum."""
    from .ergonomics import clear_span_mm
    need = asm.rig.desc.enclosure.ergonomics.min_clear_span_mm
    span = clear_span_mm(asm.layout)
    ok = span >= need - 1e-9
    return CheckResult("grip span", ok, f"{span:.0f} mm clear between the posts of {len(asm.layout.handles.poses)} "
                       f"handles (at least {need:g})", [] if ok else [
                           f"enclosure.handles.grip_length_mm: {span:.0f} mm clear between the posts, under "
                           f"{need:g} mm (enclosure.ergonomics.min_clear_span_mm): a hand does not fit"], dict(span_mm=span))


def check_stands(asm: Assembly, extra_masses=()) -> CheckResult:
    """Set down on a table (cad/ergonomics.py): it stands tilted ``min_tilt_deg`` every way and not on a
    camera; ``extra_masses``: (name, grams, rig point) added to the parts' (tests)."""
    from .ergonomics import stability
    mp = mass_properties(asm)
    m = mp["mass_g"] + sum(g for _, g, _ in extra_masses)
    com = (np.array(mp["com_mm"]) * mp["mass_g"] + sum((g * np.asarray(p, float) for _, g, p in extra_masses),
                                                       np.zeros(3))) / m
    shapes = {n.name: n.shape(asm.cache) for n in asm.nodes}
    zmin = min(bounds_of(s).lo[2] for s in shapes.values())
    bottoms = {}
    for name, s in shapes.items():
        if bounds_of(s).lo[2] <= zmin + 1.0:      # only the lowest parts can touch the table
            bottoms[name] = np.array([v.toTuple() for v in s.tessellate(0.05, 0.2)[0]])
    ok, lines, data = stability(bottoms, com, asm.rig.desc.enclosure.ergonomics.min_tilt_deg)
    return CheckResult("stands on a table", ok, lines[-2] if ok else lines[0], lines, dict(data, com_mm=com.tolist()))


def check_button_reach(asm: Assembly, button: str = "record_button") -> CheckResult:
    """The record button's actuator within a thumb's reach of a grip's surface (cad/ergonomics.py)."""
    from .ergonomics import distance_to_grip_mm, grips
    n = asm.node(button)
    tip = n.pose.apply(np.array([n.spec.stick_out_mm, 0.0, 0.0]))
    reach = asm.rig.desc.enclosure.ergonomics.thumb_reach_mm
    d = {g.name: distance_to_grip_mm(tip, g) for g in grips(asm.layout)}
    best = min(d, key=d.get) if d else None
    ok = best is not None and d[best] <= reach
    lines = [f"{g}: {v:.1f} mm from the {button}" for g, v in d.items()]
    return CheckResult("record button reach", ok, f"{d[best]:.0f} mm from {best} (a thumb reaches {reach:g} mm)" if best
                       else "no handle", lines if ok else [f"the {button} is {d[best]:.0f} mm from the nearest grip "
                                                           f"({best}); a thumb reaches {reach:g} mm "
                                                           f"(enclosure.ergonomics.thumb_reach_mm)"] + lines, d)


def check_airflow(asm: Assembly) -> CheckResult:
    """Every air path (each blower's exhaust, the devkit's intake and exhaust) free enough for its fan,
    on the B-rep and on the exported STL, and the devkit's fan inlet clear (cad/airflow.py)."""
    from .airflow import airflow_report
    r = airflow_report(asm)
    return CheckResult("airflow", not r.problems, f"{len(r.readings)} air paths free enough for their fans, the devkit's "
                       f"fan inlet {min(r.gap_brep_mm, r.gap_stl_mm):.1f} mm clear" if not r.problems else
                       f"{len(r.problems)} air path problem(s)", r.problems + r.details, r.data)


CHECKS = [check_valid, check_interference, check_min_wall, check_clearances, check_bed, check_printable, check_fov,
          check_battery, check_vents, check_airflow, check_assembly_order, check_datums, check_mass, check_grip_span, check_stands, check_button_reach, check_electrical, check_power_parts,
          check_cables, check_estimates]


def run_checks(asm: Assembly) -> list[CheckResult]:
    return [fn(asm) for fn in progress(CHECKS, desc="checks")]


def report(results: list[CheckResult], verbose: bool = False) -> str:
    lines = []
    for r in results:
        lines.append(f"[{'ok' if r.ok else 'FAIL'}] {r.name}: {r.summary}")
        shown = r.details if (verbose or not r.ok or r.name.startswith(("mass", "estimates", "minimum"))) else []
        if not r.ok and not verbose:
            shown = [d for d in r.details if d != "intended:"][:40]
        lines += [f"    {d}" for d in shown]
    failed = [r.name for r in results if not r.ok]
    lines.append(f"{len(results) - len(failed)}/{len(results)} checks passed" + (f"; failed: {', '.join(failed)}" if failed else ""))
    return "\n".join(lines) + "\n"
