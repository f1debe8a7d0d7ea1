"""Can a part print without supports? Measured on its mesh (the STL triangles, in print orientation,
bed at the lowest z), never on the B-rep it came from: pure functions over a ``(n, 3, 3)`` array.

A facet *overhangs* when it faces down more steeply than the printer's ``max_overhang_deg`` from the
vertical (a wall is 0 deg, a ceiling 90 deg) and does not lie on the bed. Overhanging facets that
share edges form a *region*. A region edge is *supported* when the facet across it runs down from it
(a wall standing under the region) or it lies on the bed. The region prints as a bridge from its
supported edges: its *span* is twice the largest distance (in plan, x-y) from any point of it to a
supported edge (a bridge between two walls W apart has span W; a ledge reaching D from its wall has
span 2 D). A region prints without support when it has supported edges and its span is at most
``max_bridge_mm``; a region with no supported edge floats.
"""
from __future__ import annotations

import math
import struct
from dataclasses import dataclass
from pathlib import Path

import numpy as np

#: facets with every vertex this close to the lowest z lie on the bed
BED_EPS_MM = 0.05
#: a facet must overhang this much past the limit to count (a 45 deg chamfer at 45 deg is printable)
ANGLE_TOL_DEG = 1.0
#: vertices closer than this are the same vertex (STL repeats every vertex per facet)
WELD_MM = 1e-4
#: plan raster of a region, for its distances to the supported edges
RASTER_MM = 0.25
#: a facet across a patch edge whose far vertex is this much lower runs down from it: a support
SUPPORT_DROP_MM = 1e-3
#: overhanging regions smaller than this are tessellation slivers, listed but never failed
MIN_REGION_MM2 = 0.5


class StlError(ValueError):
    """An STL that cannot be read; ``str()`` names the file."""


def read_stl(path: Path | str) -> np.ndarray:
    """The triangles of a binary or ASCII STL as a ``(n, 3, 3)`` float array (mm)."""
    path = Path(path)
    data = path.read_bytes()
    if len(data) >= 84:
        (n,) = struct.unpack_from("<I", data, 80)
        if 84 + 50 * n == len(data):
            rec = np.frombuffer(data, dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")]),
                                count=n, offset=84)
            return rec["v"].astype(float)
    text = data.decode("ascii", errors="replace")
    if not text.lstrip().startswith("solid"):
        raise StlError(f"{path}: neither a binary nor an ASCII STL")
    verts = [tuple(map(float, line.split()[1:4])) for line in text.splitlines() if line.strip().startswith("vertex")]
    if len(verts) % 3 or not verts:
        raise StlError(f"{path}: ASCII STL with {len(verts)} vertices, not whole triangles")
    return np.asarray(verts, dtype=float).reshape(-1, 3, 3)


@dataclass(frozen=True)
class Region:
    """One connected patch of overhanging facets."""
    area_mm2: float
    z_mm: tuple[float, float]          # lowest and highest z of the patch above the bed
    centre_mm: tuple[float, float, float]
    size_mm: tuple[float, float]       # plan extent x, y
    supported_fraction: float          # of its boundary length
    span_mm: float                     # inf when nothing supports it
    ok: bool

    def describe(self) -> str:
        span = "no supported edge (floats)" if math.isinf(self.span_mm) else f"span {self.span_mm:.1f} mm"
        c = self.centre_mm
        return (f"{self.area_mm2:.0f} mm^2 overhang at ({c[0]:.0f}, {c[1]:.0f}, {c[2]:.1f}) mm on the bed, "
                f"{self.size_mm[0]:.0f} x {self.size_mm[1]:.0f} mm, z {self.z_mm[0]:.1f}-{self.z_mm[1]:.1f} mm, {span}")


@dataclass(frozen=True)
class Printability:
    regions: tuple[Region, ...]
    bed_contact_mm2: float
    overhang_mm2: float               # all overhanging facets above the bed

    @property
    def ok(self) -> bool:
        return all(r.ok for r in self.regions)

    @property
    def failing(self) -> list[Region]:
        return [r for r in self.regions if not r.ok]

    @property
    def longest_bridge_mm(self) -> float:
        """The longest span of the patches that print (slivers under ``MIN_REGION_MM2`` aside)."""
        return max((r.span_mm for r in self.regions if r.ok and r.area_mm2 >= MIN_REGION_MM2), default=0.0)


def facet_geometry(tri: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit normals (right-hand rule, as STL orders vertices) and areas of the facets."""
    cr = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    norm = np.linalg.norm(cr, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        unit = np.where(norm[:, None] > 0, cr / norm[:, None], 0.0)
    return unit, norm / 2


def overhang_mask(tri: np.ndarray, max_overhang_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """(overhanging facets above the bed, facets on the bed)."""
    unit, area = facet_geometry(tri)
    z0 = tri[:, :, 2].min()
    on_bed = (tri[:, :, 2] <= z0 + BED_EPS_MM).all(axis=1)
    down = -unit[:, 2]
    limit = math.sin(math.radians(max_overhang_deg + ANGLE_TOL_DEG))
    return (down > limit) & ~on_bed & (area > 0), on_bed & (unit[:, 2] < -0.99)


def _weld(tri: np.ndarray) -> np.ndarray:
    """Vertex ids per facet corner, ``(n, 3)``."""
    keys = np.round(tri.reshape(-1, 3) / WELD_MM).astype(np.int64)
    _, ids = np.unique(keys, axis=0, return_inverse=True)
    return ids.reshape(-1, 3)


def analyse(tri: np.ndarray, max_overhang_deg: float, max_bridge_mm: float) -> Printability:
    """Every overhanging region of the mesh ``tri`` (print orientation, z up), measured."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    tri = np.asarray(tri, dtype=float)
    unit, area = facet_geometry(tri)
    over, bed = overhang_mask(tri, max_overhang_deg)
    z0 = tri[:, :, 2].min()
    ids = _weld(tri)
    corners = np.array([[0, 1, 2], [1, 2, 0], [2, 0, 1]])     # edge (a, b) and the opposite vertex c
    edges = np.sort(ids[:, corners[:, :2]], axis=2).reshape(-1, 2)       # (3n, 2)
    opposite = ids[:, corners[:, 2]].reshape(-1)
    facet = np.repeat(np.arange(len(tri)), 3)
    _, edge_id = np.unique(edges, axis=0, return_inverse=True)
    edge_id = edge_id.reshape(-1)
    vert_z = np.zeros(ids.max() + 1)
    vert_z[ids.reshape(-1)] = tri.reshape(-1, 3)[:, 2]
    # facets sharing an edge, both overhanging: the regions' graph
    order = np.argsort(edge_id, kind="stable")
    e_sorted, f_sorted = edge_id[order], facet[order]
    same = e_sorted[1:] == e_sorted[:-1]
    a, b = f_sorted[:-1][same], f_sorted[1:][same]
    keep = over[a] & over[b]
    n = len(tri)
    graph = coo_matrix((np.ones(int(keep.sum())), (a[keep], b[keep])), shape=(n, n))
    _, label = connected_components(graph, directed=False)
    vpos = np.zeros((vert_z.size, 3))
    vpos[ids.reshape(-1)] = tri.reshape(-1, 3)
    # per edge, the lowest opposite vertex of a facet across it that does not overhang
    low_across = np.full(edge_id.max() + 1, np.inf)
    rows = ~over[facet]
    np.minimum.at(low_across, edge_id[rows], vert_z[opposite[rows]])
    ctx = _Mesh(tri, area, edges, edge_id, facet, vert_z, vpos, low_across, z0)
    regions = [_region(ctx, np.flatnonzero((label == lab) & over), max_bridge_mm) for lab in np.unique(label[over])]
    regions.sort(key=lambda r: -r.area_mm2)
    return Printability(tuple(regions), float(area[bed].sum()), float(area[over].sum()))


@dataclass(frozen=True)
class _Mesh:
    tri: np.ndarray
    area: np.ndarray
    edges: np.ndarray        # (3n, 2) vertex ids per facet edge row
    edge_id: np.ndarray      # (3n,) the edge each row is
    facet: np.ndarray        # (3n,) the facet each row belongs to
    vert_z: np.ndarray
    vpos: np.ndarray
    low_across: np.ndarray   # per edge id
    z0: float


def _region(m: _Mesh, members: np.ndarray, max_bridge_mm: float) -> Region:
    in_region = np.zeros(len(m.tri), bool)
    in_region[members] = True
    rows = np.flatnonzero(in_region[m.facet])
    counts = np.bincount(m.edge_id[rows], minlength=m.edge_id.max() + 1)
    brows = rows[counts[m.edge_id[rows]] == 1]               # boundary: no other region facet shares it
    va, vb = m.edges[brows, 0], m.edges[brows, 1]
    seg = np.stack([m.vpos[va, :2], m.vpos[vb, :2]], axis=1)
    length = np.linalg.norm(seg[:, 1] - seg[:, 0], axis=1)
    z_edge = np.minimum(m.vert_z[va], m.vert_z[vb])
    on_bed = np.maximum(m.vert_z[va], m.vert_z[vb]) <= m.z0 + BED_EPS_MM
    supported = on_bed | (m.low_across[m.edge_id[brows]] < z_edge - SUPPORT_DROP_MM)
    total = float(length.sum())
    pts = m.tri[members].reshape(-1, 3)
    lo, hi = pts[:, :2].min(axis=0), pts[:, :2].max(axis=0)
    a = float(m.area[members].sum())
    span = _span(m.tri[members], list(seg[supported]), lo, hi)
    ok = a < MIN_REGION_MM2 or (not math.isinf(span) and span <= max_bridge_mm)
    w = m.area[members] / max(a, 1e-12)
    centre = (m.tri[members].mean(axis=1) * w[:, None]).sum(axis=0)
    return Region(a, (float(pts[:, 2].min() - m.z0), float(pts[:, 2].max() - m.z0)), tuple(map(float, centre)),
                  tuple(map(float, hi - lo)), float(length[supported].sum()) / total if total else 0.0, span, ok)


def _span(tri: np.ndarray, supported: list[np.ndarray], lo: np.ndarray, hi: np.ndarray) -> float:
    """Twice the largest plan distance from the region to its nearest supported edge (inf: none)."""
    import cv2
    if not supported:
        return math.inf
    pad = 2
    origin = lo - pad * RASTER_MM
    shape = (int(math.ceil((hi[1] - lo[1]) / RASTER_MM)) + 2 * pad + 1,
             int(math.ceil((hi[0] - lo[0]) / RASTER_MM)) + 2 * pad + 1)
    px = lambda p: np.round((np.asarray(p) - origin) / RASTER_MM).astype(np.int32)  # noqa: E731
    mask = np.zeros(shape, np.uint8)
    for t in tri:
        cv2.fillConvexPoly(mask, px(t[:, :2]), 1)
    field = np.ones(shape, np.uint8)
    for seg in supported:
        p, q = px(seg)
        cv2.line(field, tuple(map(int, p)), tuple(map(int, q)), 0, 1)
    dist = cv2.distanceTransform(field, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
    return 2 * float(dist[mask > 0].max()) * RASTER_MM if mask.any() else 0.0
