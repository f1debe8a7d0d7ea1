"""The devkit fan's intake gap under the capture card (issue 16 items 6 and 9): what stands in it.

The devkit's fan draws from its top face; over it stands the capture card, so the air reaches the fan
sideways, through the gap between devkit and card: round the fan, the side of the cylinder of the fan's
radius R and the gap's height h, pi D h. The card's standoffs (and anything else standing in the gap
under the card) block part of that side: each blocks the arc it hides as seen from the fan's axis
(its shadow on the cylinder), over its height in the gap. So the rule for what stands in the gap is an
area, not a height: the side's open area, pi D h less every shadow, is at least the fan's own free ring
pi/4 (D^2 - hub^2) (the gap is open, no grille: a ratio of 1; with nothing in it, the gap rule's h = D/4
gives pi D^2 / 4, so fixings may hide the difference). The clear height over the fan's disc (cad/airflow.py)
ignores the standoffs: this rule measures them.

Measured twice: on the B-rep (each part's common with the gap's slab under the card, the arc its
vertices and sampled edges span from the axis, merged over the parts standing at each height) and on
the exported meshes (horizontal rays from the fan's axis out to the card's edge, on an angle x height
grid, a ray blocked when it meets the mesh's section at its height: the blocked fraction of the side).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import cadquery as cq
import numpy as np

from .assembly import ORIN_NODE
from .geom import Bounds
from .solids import bounds_of, box

#: ray grid: angle step (deg) round the axis, and the height step (mm) in the gap
RAY_ANGLE_DEG, RAY_HEIGHT_MM = 0.5, 0.25
#: points sampled along every edge of a part's common with the gap (its arcs' extreme directions)
EDGE_SAMPLES = 64
#: the two readings agree when they differ by at most AGREE_ABS_MM2 plus, per part in the gap, one ray
#: cell's width of arc over the gap's height (each arc's two ends fall inside a cell: half a cell each)
AGREE_ABS_MM2 = 2.0


@dataclass(frozen=True)
class Gap:
    """The gap between the devkit's top (``z0``) and the card's underside (``z1``) over the fan's axis
    ``centre`` (x, y), the fan's ``radius`` and the card's footprint (``footprint``: the slab the air
    crosses under the card, x-y from the card, z from z0 to z1)."""
    centre: tuple[float, float]
    radius: float
    z0: float
    z1: float
    footprint: Bounds

    @property
    def height(self) -> float:
        return self.z1 - self.z0

    @property
    def side_mm2(self) -> float:
        """The cylinder's side, pi D h: the area the air enters through with nothing in the gap."""
        return 2 * math.pi * self.radius * max(0.0, self.height)

    def slab(self) -> Bounds:
        f = self.footprint
        return Bounds((f.lo[0], f.lo[1], self.z0), (f.hi[0], f.hi[1], self.z1))


@dataclass(frozen=True)
class GapReading:
    gap: Gap
    need_mm2: float
    blocked_brep_mm2: float
    blocked_stl_mm2: float
    by: tuple[str, ...]            # the parts standing in the gap

    @property
    def open_brep_mm2(self) -> float:
        return self.gap.side_mm2 - self.blocked_brep_mm2

    @property
    def open_stl_mm2(self) -> float:
        return self.gap.side_mm2 - self.blocked_stl_mm2

    @property
    def ok(self) -> bool:
        return min(self.open_brep_mm2, self.open_stl_mm2) >= self.need_mm2 - 1e-6

    @property
    def agree(self) -> bool:
        cell = math.radians(RAY_ANGLE_DEG) * self.gap.radius * self.gap.height
        return abs(self.blocked_brep_mm2 - self.blocked_stl_mm2) <= AGREE_ABS_MM2 + cell * max(1, len(self.by))


# ----------------------------------------------------------------------------- B-rep
def _arc(points: np.ndarray, centre: tuple[float, float]) -> tuple[float, float] | None:
    """The arc (start, end, radians, start < end, span < 2 pi) the points span seen from ``centre``;
    None when they surround it (the part stands on the axis: it hides every direction)."""
    a = np.arctan2(points[:, 1] - centre[1], points[:, 0] - centre[0])
    mid = math.atan2(np.sin(a).mean(), np.cos(a).mean())
    d = (a - mid + math.pi) % (2 * math.pi) - math.pi
    if d.max() - d.min() >= math.pi:          # more than a half-turn: treat as surrounding the axis
        return None
    return mid + d.min(), mid + d.max()


def _union_length(arcs: list[tuple[float, float] | None]) -> float:
    """Total angle (radians) covered by the arcs (None: the whole turn)."""
    if any(a is None for a in arcs):
        return 2 * math.pi
    pieces = []
    for lo, hi in arcs:                        # normalise to [0, 2 pi), splitting an arc over 0
        lo2 = lo % (2 * math.pi)
        hi2 = lo2 + (hi - lo)
        pieces += [(lo2, min(hi2, 2 * math.pi))] + ([(0.0, hi2 - 2 * math.pi)] if hi2 > 2 * math.pi else [])
    pieces.sort()
    total, cur_lo, cur_hi = 0.0, None, None
    for lo, hi in pieces:
        if cur_hi is None or lo > cur_hi:
            if cur_hi is not None:
                total += cur_hi - cur_lo
            cur_lo, cur_hi = lo, hi
        else:
            cur_hi = max(cur_hi, hi)
    return total + ((cur_hi - cur_lo) if cur_hi is not None else 0.0)


def _shape_points(s: cq.Shape) -> np.ndarray:
    pts = [v.toTuple() for v in s.Vertices()]
    for e in s.Edges():
        pts += [e.positionAt(t).toTuple() for t in np.linspace(0.0, 1.0, EDGE_SAMPLES)]
    return np.asarray(pts, dtype=float)


def brep_blocked_mm2(gap: Gap, shapes: dict[str, cq.Shape]) -> tuple[float, tuple[str, ...]]:
    """The side area the shapes hide (their commons with the gap's slab, merged per height), and which."""
    if gap.height <= 0:
        return 0.0, ()
    slab = gap.slab()
    tool = box(slab)
    parts = []                                   # (z_lo, z_hi, arc)
    for name, s in shapes.items():
        if not bounds_of(s).overlaps(slab):
            continue
        c = s.intersect(tool)
        if not c.Solids() or c.Volume() < 1e-6:
            continue
        b = bounds_of(c)
        parts.append((name, b.lo[2], b.hi[2], _arc(_shape_points(c), gap.centre)))
    zs = sorted({gap.z0, gap.z1, *[p[1] for p in parts], *[p[2] for p in parts]})
    area = 0.0
    for lo, hi in zip(zs, zs[1:]):
        mid = (lo + hi) / 2
        arcs = [p[3] for p in parts if p[1] <= mid <= p[2]]
        area += gap.radius * _union_length(arcs) * (hi - lo) if arcs else 0.0
    return area, tuple(p[0] for p in parts)


# ----------------------------------------------------------------------------- meshes
def _edge_distance(gap: Gap, theta: np.ndarray) -> np.ndarray:
    """How far a ray from the axis at angle ``theta`` runs before it leaves the card's footprint."""
    f, (cx, cy) = gap.footprint, gap.centre
    c, s = np.cos(theta), np.sin(theta)
    with np.errstate(divide="ignore", invalid="ignore"):
        tx = np.where(c > 0, (f.hi[0] - cx) / c, np.where(c < 0, (f.lo[0] - cx) / c, np.inf))
        ty = np.where(s > 0, (f.hi[1] - cy) / s, np.where(s < 0, (f.lo[1] - cy) / s, np.inf))
    return np.minimum(tx, ty)


def ray_grid(gap: Gap) -> tuple[np.ndarray, np.ndarray]:
    """The rays' angles (radians) and heights (cell centres)."""
    n_a = round(360 / RAY_ANGLE_DEG)
    n_z = max(1, round(gap.height / RAY_HEIGHT_MM))
    theta = (np.arange(n_a) + 0.5) * 2 * math.pi / n_a
    z = gap.z0 + (np.arange(n_z) + 0.5) * gap.height / n_z
    return theta, z


def _sections(tri: np.ndarray, z: float) -> tuple[np.ndarray, np.ndarray]:
    """The segments (ends P, Q: K x 2) where the plane at height ``z`` cuts the triangles."""
    d = tri[:, :, 2] - z
    ends = []
    for a, b in ((0, 1), (1, 2), (2, 0)):
        cross = d[:, a] * d[:, b] < 0
        t = np.where(cross, d[:, a] / np.where(cross, d[:, a] - d[:, b], 1.0), 0.0)
        ends.append((cross, tri[:, a, :2] + t[:, None] * (tri[:, b, :2] - tri[:, a, :2])))
    n = sum(c.astype(int) for c, _ in ends)
    keep = n == 2                                   # the plane crosses two edges (none runs through a vertex)
    first = np.where(ends[0][0][:, None], ends[0][1], ends[1][1])
    second = np.where((ends[0][0] & ends[1][0])[:, None], ends[1][1], ends[2][1])
    return first[keep], second[keep]


def mesh_blocked_mm2(gap: Gap, tri: np.ndarray) -> float:
    """Horizontal rays from the fan's axis to the card's edge: the blocked fraction of the side, as area.
    ``tri``: (M, 3, 3) triangles of every part but the devkit and the card. At each ray height the mesh
    is cut into segments (where the plane crosses each triangle) and each ray meets a segment when it
    crosses it before the card's edge (a triangle edge-on to the ray is no obstacle)."""
    theta, zs = ray_grid(gap)
    if len(tri) == 0 or gap.height <= 0:       # no gap: nothing to hide (and no side: the rule fails)
        return 0.0
    slab = gap.slab()
    keep = ((tri[:, :, 2].max(1) >= slab.lo[2]) & (tri[:, :, 2].min(1) <= slab.hi[2])
            & (tri[:, :, 0].max(1) >= slab.lo[0]) & (tri[:, :, 0].min(1) <= slab.hi[0])
            & (tri[:, :, 1].max(1) >= slab.lo[1]) & (tri[:, :, 1].min(1) <= slab.hi[1]))
    tri = tri[keep]
    u = np.column_stack([np.cos(theta), np.sin(theta)])          # (A, 2)
    reach = _edge_distance(gap, theta)
    c = np.asarray(gap.centre)
    blocked = 0
    for z in zs:
        p, q = _sections(tri, float(z))
        if len(p) == 0:
            continue
        p, e = p - c, q - p                                        # (K, 2)
        den = u[:, None, 0] * e[None, :, 1] - u[:, None, 1] * e[None, :, 0]          # cross(u, e): (A, K)
        ok = np.abs(den) > 1e-12
        den = np.where(ok, den, 1.0)
        t = (p[None, :, 0] * e[None, :, 1] - p[None, :, 1] * e[None, :, 0]) / den   # cross(p, e) / cross(u, e)
        s = (p[None, :, 0] * u[:, None, 1] - p[None, :, 1] * u[:, None, 0]) / den   # cross(p, u) / cross(u, e)
        hit = ok & (s >= 0) & (s <= 1) & (t > 0) & (t <= reach[:, None])
        blocked += int(hit.any(axis=1).sum())
    return blocked / (len(theta) * len(zs)) * gap.side_mm2


# ----------------------------------------------------------------------------- the reading
def gap_of(asm) -> Gap:
    """The assembly's gap: over the devkit node's top, under the card node, round the devkit's fan."""
    ob = bounds_of(asm.node(ORIN_NODE).shape(asm.cache))
    cb = bounds_of(asm.node(CARD_NODE).shape(asm.cache))
    return Gap((ob.centre[0], ob.centre[1]), asm.layout.compute.fan_diameter / 2, ob.hi[2], cb.lo[2], cb)


#: the node the fan's air passes under
CARD_NODE = "zed_link_quad"


def fixings(asm) -> set[str]:
    """The card's standoffs and the screws into them: what this rule measures, not the clear height."""
    so = {n.name for n in asm.nodes if n.props.get("kind") == "standoff"}
    return so | {n.name for n in asm.nodes if n.props.get("host") in so}


def need_mm2(asm) -> float:
    """The fan's free ring, pi/4 (D^2 - hub^2): what the gap's open side must pass."""
    cp = asm.layout.compute
    return math.pi / 4 * (cp.fan_diameter ** 2 - cp.fan_hub ** 2)


def gap_reading(gap: Gap, need: float, shapes: dict[str, cq.Shape], tri: np.ndarray) -> GapReading:
    """Both readings of what ``shapes`` (B-rep) and ``tri`` (their meshes) hide of the gap's side."""
    brep, by = brep_blocked_mm2(gap, shapes)
    return GapReading(gap, need, brep, mesh_blocked_mm2(gap, tri), by)


def gap_problems(g: GapReading) -> list[str]:
    """One line per way the reading fails the rule."""
    out = []
    if not g.ok:
        out.append(f"orin_intake: {', '.join(g.by) or 'parts'} under the card hide "
                   f"{max(g.blocked_brep_mm2, g.blocked_stl_mm2):.0f} mm^2 of the {g.gap.side_mm2:.0f} mm^2 round the "
                   f"devkit's fan (pi D h, h = {g.gap.height:.1f} mm): {min(g.open_brep_mm2, g.open_stl_mm2):.0f} mm^2 "
                   f"open, under its free ring {g.need_mm2:.0f} mm^2: move them out from the fan or raise the card")
    if not g.agree:
        out.append(f"orin_intake: the B-rep ({g.blocked_brep_mm2:.1f} mm^2) and the meshes ({g.blocked_stl_mm2:.1f} "
                   f"mm^2) disagree on the area hidden round the devkit's fan")
    return out
