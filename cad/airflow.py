"""Air paths through the case (issue 16 item 6): what each fan needs, what the case lets through.

Paths, each moved by one fan, each a set of the case's vent slots found by where they are (the wall
they cross and the part beside them), not by the layout code that placed them:

- ``blower_<side>_intake``: the 3010 blower's inlet (``BlowerFan.inlet_diameter_mm``, on its +z
  face) faces a wall of the case; the slots in that wall whose centres lie within
  ``INTAKE_REACH_DIAMETERS`` x the inlet's diameter of its axis feed it (``cad/layout/case.py``: a
  suction opening's draw falls off within about a diameter); need: ``min_area_ratio`` x the inlet's
  area (``BlowerFan.inlet_area_mm2``);
- ``blower_<side>_exhaust``: the 3010 blower's outlet, through its fin bank, out of the front wall
  slots on its side and the side wall slots ahead of the fan; need: ``min_area_ratio`` x the
  outlet's area (``Fan.outlet_area_mm2``, from ``BlowerFan.outlet``);
- ``orin_intake``: the devkit's own fan draws from its top face (an estimate,
  ``parts.jetson_agx_orin.dims``) through the roof slots over it, then round the capture card's
  edges into the gap between card and devkit; need: ``min_area_ratio`` x the fan's free ring,
  pi/4 (D^2 - hub^2), and a clear height over the fan of ``inlet_gap_ratio`` x D (the card's
  standoffs and their screws excepted: what stands in the gap round the fan is measured by its own
  rule, the side area it hides, ``cad/inlet_gap.py``);
- ``orin_exhaust``: its heat sink blows out of its +-y faces, through the side wall slots (tray and
  lid) beside it; same need as the intake.

The DC-DC converter moves no air of its own; it loses ``load x (1 / efficiency - 1)`` as heat (cad/electrical.py's
budget). It must stand in a stream (``converter_stream``): in front of one of the devkit's exhaust faces, between
it and the side wall, overlapping that face, with ``orin_exhaust`` slots over it (within its length, above its
top) for the stream to leave by after passing it. That is a rule of presence, not of flow: the free area of
those slots is measured (both ways, as the paths) and reported beside the loss, and fails only when it is none.

Both rules are rules of thumb (docs/cad.md, "Cooling the computer"). Each free area is measured
twice: on the B-rep (the built case halves sectioned at each wall's mid-plane, inside each slot's
window, the slot grown by one ray cell: the window's area less the material's) and on the case halves
exported to STL and read back (a grid of rays along the wall's normal through each window, through
the whole wall, counting the cells whose ray no triangle stops). The clear height over the devkit's fan is
measured the same two ways: the lowest point of any part inside the column over the fan (B-rep
common), and rays cast up from the fan's disc through every part's exported mesh.
"""
from __future__ import annotations

import math
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import cadquery as cq
import numpy as np

from . import inlet_gap
from .layout.case import intake_reach_mm
from .geom import Bounds
from .solids import bounds_of, box, common_volume_mm3, cylinder

#: the B-rep section is a slab this thin at the wall's mid-plane (its volume / thickness = its area)
SECTION_MM = 0.02
#: ray grid pitch in the wall's plane; cell centres, aligned with each window's corner
RAY_PITCH_MM = 0.25
#: rays start and end this far outside both faces of the wall
RAY_OVERRUN_MM = 0.5
#: the STL's chordal and angular tolerance (the exports' default)
STL_TOLERANCE_MM, STL_ANGULAR_RAD = 0.1, 0.2
#: the two measurements agree when they differ by at most this fraction, plus AGREE_ABS_MM2 per window
AGREE_REL, AGREE_ABS_MM2 = 0.01, 1.0
#: the case's halves (the parts the vents are cut in)
CASE_NODES = ("case_lower", "case_lid")
#: the node whose fan draws through the roof, and what may stand in its inlet's column
ORIN_NODE = "jetson_agx_orin"
#: the node that loses heat without a fan of its own and must stand in the devkit's exhaust stream
CONVERTER_NODE = "dc_converter"


@dataclass(frozen=True)
class Window:
    """One slot's opening in a wall: ``box`` spans the wall's thickness along ``axis`` (0 front, 1 side,
    2 roof) and, in the wall's plane, the slot grown by one ray cell (``step``, per in-plane axis, the
    slot's size split into whole cells of about ``RAY_PITCH_MM``), so an opening wider or shifted
    shows, and the slot's edges fall on cell edges: no cell straddles one."""
    box: Bounds
    axis: int
    step: tuple[float, float]

    @property
    def area_mm2(self) -> float:
        s = self.box.size
        return float(np.prod([s[k] for k in range(3) if k != self.axis]))


@dataclass(frozen=True)
class AirPath:
    name: str
    fan: str                       # what moves the air, in words
    fan_area_mm2: float            # the fan's own flow area (outlet, or the free ring)
    need_mm2: float                # min_area_ratio x fan_area_mm2
    windows: tuple[Window, ...]
    where: str                     # the walls the path crosses, in words


@dataclass
class PathReading:
    path: AirPath
    brep_mm2: float
    stl_mm2: float
    rays: int

    @property
    def ok(self) -> bool:
        return self.brep_mm2 >= self.path.need_mm2 - 1e-6 and self.stl_mm2 >= self.path.need_mm2 - 1e-6

    @property
    def agree(self) -> bool:
        tol = AGREE_REL * max(self.brep_mm2, self.stl_mm2) + AGREE_ABS_MM2 * max(1, len(self.path.windows))
        return abs(self.brep_mm2 - self.stl_mm2) <= tol


@dataclass
class StreamReading:
    """Where a part without a fan of its own (the converter) loses its heat: the exhaust face it stands in front
    of ("" when none) and the slots over it that stream leaves by, their free area both ways."""
    part: str
    loss_w: float
    beside: str
    windows: tuple[Window, ...]
    brep_mm2: float = 0.0
    stl_mm2: float = 0.0

    @property
    def ok(self) -> bool:
        return bool(self.beside) and bool(self.windows) and min(self.brep_mm2, self.stl_mm2) > 0.0


@dataclass
class AirflowReport:
    readings: list[PathReading]
    gap_brep_mm: float
    gap_stl_mm: float
    gap_need_mm: float
    gap_by: str                    # the part nearest over the fan
    problems: list[str] = field(default_factory=list)
    details: list[str] = field(default_factory=list)
    data: dict = field(default_factory=dict)
    side: "inlet_gap.GapReading | None" = None    # what stands in the gap round the fan (cad/inlet_gap.py)
    converter: StreamReading | None = None        # the converter's heat, in the devkit's exhaust stream


# ----------------------------------------------------------------------------- the paths
def _wall_axis(v: Bounds, outer: Bounds) -> int | None:
    """The wall a slot's cutting box crosses: 0 the front, 1 a side, 2 the roof (None: another)."""
    if v.lo[0] < outer.hi[0] < v.hi[0]:
        return 0
    if v.lo[1] < outer.hi[1] < v.hi[1] or v.lo[1] < outer.lo[1] < v.hi[1]:
        return 1
    if v.lo[2] < outer.hi[2] < v.hi[2]:
        return 2
    return None


def _window(v: Bounds, axis: int, inner: Bounds, outer: Bounds) -> Window:
    """The slot clipped to its wall's thickness and grown by one ray cell in the wall's plane."""
    lo, hi, step = list(v.lo), list(v.hi), []
    for k in range(3):
        if k == axis:
            side_hi = v.hi[k] > outer.hi[k]
            lo[k], hi[k] = (inner.hi[k], outer.hi[k]) if side_hi else (outer.lo[k], inner.lo[k])
        else:
            size = hi[k] - lo[k]
            step.append(size / max(1, round(size / RAY_PITCH_MM)))
            lo[k], hi[k] = lo[k] - step[-1], hi[k] + step[-1]
    return Window(Bounds(tuple(lo), tuple(hi)), axis, (step[0], step[1]))


def inlet_of(part, pose) -> tuple[np.ndarray, np.ndarray]:
    """A blower's inlet in the rig frame: its centre (on the fan's +z face, ``cad/bought/fan.py``'s frame)
    and the unit direction it faces. Shapes (3,), (3,)."""
    centre = np.asarray(pose.apply(np.array([0.0, 0.0, part.size[2] / 2])), dtype=float)
    return centre, np.asarray(pose.R, dtype=float) @ np.array([0.0, 0.0, 1.0])


def feeds_inlet(slot: Bounds, axis: int, outer: Bounds, centre: np.ndarray, facing: np.ndarray, reach_mm: float) -> bool:
    """Whether a slot feeds an inlet at ``centre`` facing ``facing``: it crosses the wall the inlet faces
    (the wall across the inlet's main axis, on its side of the case) and its centre lies, in that wall's
    plane, within ``reach_mm`` of the inlet's axis."""
    k = int(np.argmax(np.abs(facing)))
    if axis != k or np.sign(slot.centre[k] - outer.centre[k]) != np.sign(facing[k]):
        return False
    u, w = (j for j in range(3) if j != k)
    return math.hypot(slot.centre[u] - centre[u], slot.centre[w] - centre[w]) <= reach_mm + 1e-9


def air_paths(lay) -> list[AirPath]:
    """The case's air paths, their needs and the windows of the slots each passes (see the module)."""
    v = lay.rig.desc.enclosure.vents
    o, i = lay.case.outer, lay.case.interior
    slots = [(b, _wall_axis(b, o)) for b in lay.case.vents]
    slots = [(b, a) for b, a in slots if a is not None]
    win = lambda b, a: _window(b, a, i, o)     # noqa: E731
    paths = []
    part, reach = lay.cooling.part, intake_reach_mm(lay.rig)
    for side, f in lay.cooling.fans.items():
        centre, facing = inlet_of(part, f.pose)
        ws = [win(b, a) for b, a in slots if feeds_inlet(b, a, o, centre, facing, reach)]
        paths.append(AirPath(f"blower_{side}_intake", f"fan_{side}'s {part.inlet_diameter_mm:g} mm inlet",
                             part.inlet_area_mm2, v.min_area_ratio * part.inlet_area_mm2, tuple(ws),
                             f"wall its inlet faces, within {reach:g} mm of the inlet's axis"))
    for side, f in lay.cooling.fans.items():
        ws = [win(b, a) for b, a in slots
              if (a == 0 and np.sign(b.centre[1]) == f.sign)
              or (a == 1 and np.sign(b.centre[1]) == f.sign and b.lo[0] >= f.box.hi[0])]
        paths.append(AirPath(f"blower_{side}_exhaust", f"fan_{side}'s outlet", f.outlet_area_mm2,
                             v.min_area_ratio * f.outlet_area_mm2, tuple(ws), "front wall and side wall ahead of the fan"))
    cp = lay.compute
    ring = math.pi / 4 * (cp.fan_diameter ** 2 - cp.fan_hub ** 2)
    b = cp.orin_box
    intake = [win(s, a) for s, a in slots if a == 2 and b.lo[0] <= s.centre[0] <= b.hi[0]]
    exhaust = [win(s, a) for s, a in slots if a == 1 and b.lo[0] <= s.lo[0] and s.hi[0] <= b.hi[0]]
    fan = f"the devkit's {cp.fan_diameter:g} mm fan (free ring, estimate)"
    paths.append(AirPath("orin_intake", fan, ring, v.min_area_ratio * ring, tuple(intake), "roof over the devkit"))
    paths.append(AirPath("orin_exhaust", fan, ring, v.min_area_ratio * ring, tuple(exhaust), "side walls beside the devkit"))
    return paths


def converter_stream(lay, paths: list[AirPath], part: str = CONVERTER_NODE) -> tuple[str, tuple[Window, ...]]:
    """The devkit's exhaust face the converter stands in front of (``"+y"`` / ``"-y"``; ``""`` when none): the
    converter between that face and the side wall, overlapping it along x and z; and the windows of
    ``orin_exhaust`` on that side over the converter (overlapping its length, wholly above its top), which the
    stream leaving that face passes it to reach."""
    cb, ob = lay.power.converter_box, lay.compute.orin_box
    s = 1.0 if cb.centre[1] > ob.centre[1] else -1.0
    face = ob.hi[1] if s > 0 else ob.lo[1]
    wall = lay.case.interior.hi[1] if s > 0 else lay.case.interior.lo[1]
    between = all(min(face, wall) - 1e-6 <= y <= max(face, wall) + 1e-6 for y in (cb.lo[1], cb.hi[1]))
    overlaps = all(cb.lo[k] < ob.hi[k] and ob.lo[k] < cb.hi[k] for k in (0, 2))
    if not (between and overlaps):
        return "", ()
    exhaust = next((p for p in paths if p.name == "orin_exhaust"), None)
    ws = tuple(w for w in (exhaust.windows if exhaust else ())
               if np.sign(w.box.centre[1]) == s and w.box.lo[0] < cb.hi[0] and cb.lo[0] < w.box.hi[0]
               and w.box.lo[2] >= cb.hi[2] - 1e-6)
    return ("+y" if s > 0 else "-y"), ws


# ----------------------------------------------------------------------------- B-rep measurements
def brep_free_area_mm2(case_shapes: list[cq.Shape], windows: tuple[Window, ...]) -> float:
    """The windows' area less the case's material in them, sectioned at each wall's mid-plane (a
    slab ``SECTION_MM`` thick: one boolean per case half for all the path's windows)."""
    slabs = []
    for w in windows:
        lo, hi = list(w.box.lo), list(w.box.hi)
        mid = (lo[w.axis] + hi[w.axis]) / 2
        lo[w.axis], hi[w.axis] = mid - SECTION_MM / 2, mid + SECTION_MM / 2
        slabs.append(box(Bounds(tuple(lo), tuple(hi))))
    if not slabs:
        return 0.0
    tool = cq.Compound.makeCompound(slabs)
    tb = bounds_of(tool)
    material = 0.0
    for s in case_shapes:
        if bounds_of(s).overlaps(tb):
            material += common_volume_mm3(s, tool) / SECTION_MM
    return sum(w.area_mm2 for w in windows) - material


def brep_clear_height_mm(shapes: dict[str, cq.Shape], base_z: float, centre: tuple[float, float], diameter: float,
                         height: float) -> tuple[float, str]:
    """The lowest point of any shape inside the column of ``diameter`` standing on ``base_z`` over
    ``centre`` (``height`` tall), above ``base_z``; and which shape it is."""
    col = cylinder(diameter, height, (centre[0], centre[1], base_z + 1e-3))
    cb = bounds_of(col)
    best, by = height, ""
    for name, s in shapes.items():
        if not bounds_of(s).overlaps(cb):
            continue
        c = s.intersect(col)
        if c.Solids() and c.Volume() > 1e-6:
            z = bounds_of(c).lo[2] - base_z
            if z < best:
                best, by = z, name
    return best, by


# ----------------------------------------------------------------------------- STL measurements
def stl_triangles(shape: cq.Shape, path: Path) -> np.ndarray:
    """``shape`` exported to STL at ``path`` and read back (the file, not the B-rep)."""
    from .printability import read_stl
    cq.exporters.export(shape, str(path), "STL", tolerance=STL_TOLERANCE_MM, angularTolerance=STL_ANGULAR_RAD)
    return read_stl(path)


def first_hits(tri: np.ndarray, axis: int, uv: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """For rays along ``axis`` (+) at in-plane points ``uv`` (N x 2, the other two axes in order), the
    lowest coordinate along ``axis`` in [lo, hi] where each meets a triangle of ``tri`` (inf: none).
    A ray meets a triangle when its point lies in the triangle's projection (edges included)."""
    out = np.full(len(uv), np.inf)
    if len(tri) == 0 or len(uv) == 0:
        return out
    ax = [k for k in range(3) if k != axis]
    p = tri[:, :, ax]                                   # (M, 3, 2)
    d = tri[:, :, axis]                                 # (M, 3)
    keep = ((p[:, :, 0].max(1) >= uv[:, 0].min()) & (p[:, :, 0].min(1) <= uv[:, 0].max())
            & (p[:, :, 1].max(1) >= uv[:, 1].min()) & (p[:, :, 1].min(1) <= uv[:, 1].max())
            & (d.max(1) >= lo) & (d.min(1) <= hi))
    p, d = p[keep], d[keep]
    if len(p) == 0:
        return out
    a, b, c = p[:, 0], p[:, 1], p[:, 2]
    area = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    ok = np.abs(area) > 1e-12                           # a triangle edge-on to the ray is no obstacle
    a, b, c, d, area = a[ok], b[ok], c[ok], d[ok], area[ok]
    for k0 in range(0, len(uv), 4096):
        q = uv[k0:k0 + 4096, None, :]                   # (N, 1, 2)
        w0 = ((b[:, 0] - q[..., 0]) * (c[:, 1] - q[..., 1]) - (b[:, 1] - q[..., 1]) * (c[:, 0] - q[..., 0])) / area
        w1 = ((c[:, 0] - q[..., 0]) * (a[:, 1] - q[..., 1]) - (c[:, 1] - q[..., 1]) * (a[:, 0] - q[..., 0])) / area
        w2 = 1.0 - w0 - w1
        eps = -1e-9
        inside = (w0 >= eps) & (w1 >= eps) & (w2 >= eps)
        z = w0 * d[:, 0] + w1 * d[:, 1] + w2 * d[:, 2]
        z = np.where(inside & (z >= lo) & (z <= hi), z, np.inf)
        out[k0:k0 + 4096] = z.min(axis=1)
    return out


def _grid(w: Window) -> tuple[np.ndarray, float]:
    """Cell centres over the window's in-plane extent (cells of the window's ``step``), and each
    cell's area."""
    ax = [k for k in range(3) if k != w.axis]
    step = list(w.step)
    n = [max(1, round(w.box.size[k] / d)) for k, d in zip(ax, step)]
    u = w.box.lo[ax[0]] + (np.arange(n[0]) + 0.5) * step[0]
    v = w.box.lo[ax[1]] + (np.arange(n[1]) + 0.5) * step[1]
    uu, vv = np.meshgrid(u, v, indexing="ij")
    return np.column_stack([uu.ravel(), vv.ravel()]), step[0] * step[1]


def stl_free_area_mm2(case_tri: np.ndarray, windows: tuple[Window, ...]) -> tuple[float, int]:
    """Rays along each window's wall normal, through the whole wall and ``RAY_OVERRUN_MM`` beyond both
    faces: the area of the cells whose ray no triangle of the case's mesh stops; and the ray count."""
    free, rays = 0.0, 0
    for w in windows:
        uv, cell = _grid(w)
        hit = first_hits(case_tri, w.axis, uv, w.box.lo[w.axis] - RAY_OVERRUN_MM, w.box.hi[w.axis] + RAY_OVERRUN_MM)
        free += float(np.isinf(hit).sum()) * cell
        rays += len(uv)
    return free, rays


def fan_disc_points(centre: tuple[float, float], diameter: float) -> np.ndarray:
    """Ray origins (x, y) over the fan's disc, ``RAY_PITCH_MM`` x 4 apart."""
    step = RAY_PITCH_MM * 4
    r = diameter / 2
    g = np.arange(-r + step / 2, r, step)
    xx, yy = np.meshgrid(g, g, indexing="ij")
    inside = xx ** 2 + yy ** 2 <= r * r
    return np.column_stack([xx[inside] + centre[0], yy[inside] + centre[1]])


# ----------------------------------------------------------------------------- the report
def _shared_slots(paths: list[AirPath]) -> list[str]:
    """One line per slot that two paths count (an opening's area feeds one fan, or it is counted twice)."""
    by: dict[Bounds, list[str]] = {}
    for p in paths:
        for w in p.windows:
            by.setdefault(w.box, []).append(p.name)
    return [f"the slot at ({', '.join(f'{c:.1f}' for c in b.centre)}) mm is counted by {' and '.join(names)}: "
            f"an opening feeds one path" for b, names in by.items() if len(names) > 1]


def airflow_report(asm, paths: list[AirPath] | None = None) -> AirflowReport:
    """Every air path's free area on the B-rep and the STL against its need, and the clear height over
    the devkit's fan, measured on the assembly's parts (so a part moved or a slot filled shows)."""
    lay = asm.layout
    rig = lay.rig
    paths = air_paths(lay) if paths is None else paths
    case_shapes = [asm.node(n).shape(asm.cache) for n in CASE_NODES]
    cp = lay.compute
    orin = asm.node(ORIN_NODE)
    ob = bounds_of(orin.shape(asm.cache))
    centre = (ob.centre[0], ob.centre[1])
    height = lay.case.outer.hi[2] + 50.0 - ob.hi[2]
    fix = inlet_gap.fixings(asm)
    others = {n.name: n.shape(asm.cache) for n in asm.nodes if n.name != ORIN_NODE and n.name not in fix}
    gap = inlet_gap.gap_of(asm)
    in_gap = {n.name: n.shape(asm.cache) for n in asm.nodes if n.name not in (ORIN_NODE, inlet_gap.CARD_NODE)
              and n.name not in CASE_NODES and bounds_of(n.shape(asm.cache)).overlaps(gap.slab())}
    gap_need = rig.desc.enclosure.vents.inlet_gap_ratio * cp.fan_diameter
    gap_brep, gap_by = brep_clear_height_mm(others, ob.hi[2], centre, cp.fan_diameter, height)
    readings = []
    with tempfile.TemporaryDirectory(prefix="rig-airflow-") as tmp:
        case_tri = np.concatenate([stl_triangles(s, Path(tmp) / f"{n}.stl") for n, s in zip(CASE_NODES, case_shapes)])
        for p in paths:
            free, rays = stl_free_area_mm2(case_tri, p.windows)
            readings.append(PathReading(p, brep_free_area_mm2(case_shapes, p.windows), free, rays))
        beside, cws = converter_stream(lay, paths)
        conv = StreamReading(CONVERTER_NODE, _converter_loss_w(asm), beside, cws)
        if cws:
            conv.brep_mm2 = brep_free_area_mm2(case_shapes, cws)
            conv.stl_mm2 = stl_free_area_mm2(case_tri, cws)[0]
        col = Bounds((centre[0] - cp.fan_diameter / 2, centre[1] - cp.fan_diameter / 2, ob.hi[2]),
                     (centre[0] + cp.fan_diameter / 2, centre[1] + cp.fan_diameter / 2, ob.hi[2] + height))
        pts = fan_disc_points(centre, cp.fan_diameter)
        hits = np.full(len(pts), np.inf)
        for k, (name, s) in enumerate(others.items()):
            if bounds_of(s).overlaps(col):
                tri = stl_triangles(s, Path(tmp) / f"gap_{k}.stl")
                hits = np.minimum(hits, first_hits(tri, 2, pts, ob.hi[2] + 1e-3, ob.hi[2] + height))
        gap_tri = [case_tri] + [stl_triangles(s, Path(tmp) / f"in_gap_{k}.stl") for k, s in enumerate(in_gap.values())]
        side = inlet_gap.gap_reading(gap, inlet_gap.need_mm2(asm), {**dict(zip(CASE_NODES, case_shapes)), **in_gap},
                                     np.concatenate(gap_tri))
    gap_stl = float(hits.min() - ob.hi[2]) if np.isfinite(hits).any() else height
    r = AirflowReport(readings, gap_brep, gap_stl, gap_need, gap_by, side=side, converter=conv)
    ratio = rig.desc.enclosure.vents.min_area_ratio
    r.problems += _shared_slots(paths)
    for g in readings:
        p = g.path
        r.details.append(f"{p.name}: {g.brep_mm2:.0f} mm^2 free (B-rep) / {g.stl_mm2:.0f} mm^2 (STL, {g.rays} rays) "
                         f"through {len(p.windows)} slots in the {p.where}; need {p.need_mm2:.0f} mm^2 = {ratio:g} x "
                         f"{p.fan_area_mm2:.0f} mm^2 ({p.fan})")
        if not g.ok:
            r.problems.append(f"{p.name}: {min(g.brep_mm2, g.stl_mm2):.0f} mm^2 free through the {p.where}, under "
                              f"{p.need_mm2:.0f} mm^2 = {ratio:g} x {p.fan_area_mm2:.0f} mm^2 ({p.fan}; "
                              f"enclosure.vents.min_area_ratio): add or open slots")
        if not g.agree:
            r.problems.append(f"{p.name}: the B-rep ({g.brep_mm2:.1f} mm^2) and the exported STL ({g.stl_mm2:.1f} mm^2) "
                              f"disagree on its free area")
    r.details.append(f"orin_intake: {gap_brep:.1f} mm clear over the devkit's fan (B-rep) / {gap_stl:.1f} mm (STL rays, "
                     f"{len(pts)}), nearest {gap_by or 'nothing'}; need {gap_need:.1f} mm = "
                     f"{rig.desc.enclosure.vents.inlet_gap_ratio:g} x its {cp.fan_diameter:g} mm diameter")
    if min(gap_brep, gap_stl) < gap_need - 1e-6:
        r.problems.append(f"orin_intake: {gap_by or 'a part'} is {min(gap_brep, gap_stl):.1f} mm over the devkit's fan "
                          f"inlet, under {gap_need:.1f} mm = {rig.desc.enclosure.vents.inlet_gap_ratio:g} x its "
                          f"{cp.fan_diameter:g} mm diameter (enclosure.vents.inlet_gap_ratio): raise it")
    r.details.append(f"orin_intake: {side.open_brep_mm2:.0f} mm^2 open (B-rep) / {side.open_stl_mm2:.0f} mm^2 (rays) of the "
                     f"{side.gap.side_mm2:.0f} mm^2 round the devkit's fan under the card ({', '.join(side.by) or 'nothing'} "
                     f"in the gap: {side.blocked_brep_mm2:.0f} / {side.blocked_stl_mm2:.0f} mm^2 hidden); need "
                     f"{side.need_mm2:.0f} mm^2, its free ring")
    r.problems += inlet_gap.gap_problems(side)
    if abs(gap_brep - gap_stl) > STL_TOLERANCE_MM + 1e-3:
        r.problems.append(f"orin_intake: the B-rep ({gap_brep:.2f} mm) and the STL ({gap_stl:.2f} mm) disagree on the "
                          f"clear height over the devkit's fan")
    where = (f"in front of the devkit's {conv.beside} exhaust face" if conv.beside
             else "beside no exhaust face of the devkit")
    r.details.append(f"{conv.part}: loses {conv.loss_w:.1f} W; stands {where}; {len(conv.windows)} orin_exhaust slots "
                     f"over it, {conv.brep_mm2:.0f} mm^2 free (B-rep) / {conv.stl_mm2:.0f} mm^2 (STL)")
    if not conv.ok:
        r.problems.append(f"{conv.part}: loses {conv.loss_w:.1f} W but stands in no air path: " +
                          ("it is not between an exhaust face of the devkit and the side wall" if not conv.beside
                           else "no orin_exhaust slot lies over it for the devkit's stream to leave by")
                          + " (cad/layout/power.py places it, cad/layout/case.py the slots)")
    r.data = {g.path.name: dict(brep_mm2=round(g.brep_mm2, 1), stl_mm2=round(g.stl_mm2, 1), need_mm2=round(g.path.need_mm2, 1),
                                fan_area_mm2=round(g.path.fan_area_mm2, 1), slots=len(g.path.windows), rays=g.rays)
              for g in readings}
    r.data["orin_inlet_gap"] = dict(brep_mm=round(gap_brep, 2), stl_mm=round(gap_stl, 2), need_mm=round(gap_need, 2),
                                    nearest=gap_by)
    r.data["orin_inlet_side"] = dict(side_mm2=round(side.gap.side_mm2, 1), open_brep_mm2=round(side.open_brep_mm2, 1),
                                     open_stl_mm2=round(side.open_stl_mm2, 1), need_mm2=round(side.need_mm2, 1),
                                     in_gap=list(side.by))
    r.data["converter_stream"] = dict(loss_w=round(conv.loss_w, 2), beside=conv.beside, slots=len(conv.windows),
                                      brep_mm2=round(conv.brep_mm2, 1), stl_mm2=round(conv.stl_mm2, 1))
    return r


def _converter_loss_w(asm) -> float:
    """What the converter turns into heat at the rig's load: battery power less load (cad/electrical.py)."""
    from .electrical import budget, power_counts
    b = budget(asm.rig, power_counts(asm))
    return b.battery_w - b.load_w
