"""The cables seen from their meshes (tests only): an independent path beside ``cad/cables.py``'s B-rep check.

Each swept cable is exported to STL and read back by trimesh; from the triangles alone (numpy and trimesh, no
call into the check's code) this module finds the tube's two end caps, marches its centre line through plane
sections, fits circles to the bends, measures its length two ways (the centre line's chords; the volume over
the cap's area) and tests points inside the tube for containment in other meshes (ray parity, trimesh's ray
caster with the grid broad phase of ``tests/cad/trimesh_rays.py``: no rtree here).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh
from trimesh.ray.ray_triangle import ray_triangle_id

from tests.cad.trimesh_rays import TriangleBoxes

#: the cables' STL: finer than the parts' (the centre line and the bends' radii are read off it)
CABLE_TOLERANCE_MM, CABLE_ANGULAR_RAD = 0.01, 0.1
#: the parts' STL, as the exports write them
PART_TOLERANCE_MM, PART_ANGULAR_RAD = 0.1, 0.2
#: a plane section's step along the centre line
STEP_MM = 0.25
#: the points of one bend see their circles' centres within this share of its radius of the run's mean centre
SAME_CENTRE_SHARE = 0.25
#: the containment rays' direction: off every axis, so no ray runs along a box's edge or face
RAY_DIR = np.array([0.0123, 0.0371, 1.0]) / np.linalg.norm([0.0123, 0.0371, 1.0])


def read_stl(shape, path: Path, tolerance: float, angular: float) -> trimesh.Trimesh:
    """``shape`` (a CadQuery shape) exported to STL at ``path`` and read back by trimesh (the file, not the B-rep)."""
    import cadquery as cq
    cq.exporters.export(shape, str(path), "STL", tolerance=tolerance, angularTolerance=angular)
    return trimesh.load(str(path))


# ----------------------------------------------------------------------------- caps and sections
@dataclass(frozen=True)
class Cap:
    centre: np.ndarray     # (3,)
    normal: np.ndarray     # (3,) outward
    area_mm2: float


def end_caps(mesh: trimesh.Trimesh) -> list[Cap]:
    """The tube's flat end faces: the groups of triangles sharing one plane (normal and offset) whose area
    is a disc's (their extent squared x pi / 4 within 5 %). Every other face of a swept circle is curved."""
    n = mesh.face_normals
    off = np.einsum("ij,ij->i", n, mesh.triangles_center)
    keys = np.round(np.column_stack([n * 1e3, off * 10]), 0)
    _, inv = np.unique(keys, axis=0, return_inverse=True)
    inv = inv.ravel()
    caps = []
    for g in np.flatnonzero(np.bincount(inv) >= 8):      # the planes of 8 triangles or more, in order
        idx = np.flatnonzero(inv == g)
        area = float(mesh.area_faces[idx].sum())
        pts = mesh.triangles[idx].reshape(-1, 3)
        width = float(np.ptp(pts, axis=0).max())
        if abs(area - np.pi / 4 * width ** 2) <= 0.05 * area:
            w = mesh.area_faces[idx]
            centre = (mesh.triangles_center[idx] * w[:, None]).sum(0) / w.sum()
            caps.append(Cap(centre, n[idx[0]] / np.linalg.norm(n[idx[0]]), area))
    return caps


def plane_cut(mesh: trimesh.Trimesh, origin: np.ndarray, normal: np.ndarray,
              faces: np.ndarray | None = None) -> np.ndarray:
    """The segments (K, 2, 3) where the plane through ``origin`` with ``normal`` cuts the mesh's triangles (those of
    ``faces``, indices in ascending order, when given: the segments of those triangles, in the same order)."""
    tri = mesh.triangles if faces is None else mesh.triangles[faces]
    o, n = origin, normal
    d = (tri[..., 0] - o[0]) * n[0] + (tri[..., 1] - o[1]) * n[1] + (tri[..., 2] - o[2]) * n[2]   # (N, 3) signed
    cut = (d.min(1) < 0) & (d.max(1) > 0)
    tri, d = tri[cut], d[cut]
    pts = []
    for a, b in ((0, 1), (1, 2), (2, 0)):
        da, db = d[:, a], d[:, b]
        t = np.where((da < 0) != (db < 0), da / np.where(da == db, 1.0, da - db), np.nan)
        pts.append(tri[:, a] + t[:, None] * (tri[:, b] - tri[:, a]))
    pts = np.stack(pts, axis=1)                                 # (K, 3 edges, 3)
    ok = ~np.isnan(pts[..., 0])
    pts, ok = pts[ok.sum(1) == 2], ok[ok.sum(1) == 2]           # a plane through a vertex cuts one edge: skip it
    two = np.argsort(~ok, axis=1, kind="stable")[:, :2]         # the two edges the plane crosses
    return np.take_along_axis(pts, two[..., None], axis=1)


class NearFaces:
    """The triangles of a mesh whose boxes meet the cube of half-side ``half_mm`` around a point (ascending
    indices), each query filtered from the triangles near the last point the box was gathered around (within
    ``slack_mm`` of it on every axis, so that cube holds the query's): a centre line marches in small steps, and
    a plane section of the whole mesh at every step was most of the cable tests' time."""

    def __init__(self, mesh: trimesh.Trimesh, half_mm: float, slack_mm: float):
        tri = mesh.triangles
        self.lo, self.hi = tri.min(axis=1), tri.max(axis=1)
        self.half, self.slack = half_mm, slack_mm
        self.centre: np.ndarray | None = None
        self.near = np.zeros(0, int)

    def __call__(self, q: np.ndarray) -> np.ndarray:
        if self.centre is None or np.abs(q - self.centre).max() > self.slack:
            self.centre, h = np.array(q, float), self.half + self.slack
            self.near = np.flatnonzero(np.all(self.lo <= q + h, axis=1) & np.all(self.hi >= q - h, axis=1))
        s = self.near
        return s[np.all(self.lo[s] <= q + self.half, axis=1) & np.all(self.hi[s] >= q - self.half, axis=1)]


def ring_centre(segments: np.ndarray, near: np.ndarray, within_mm: float) -> np.ndarray | None:
    """The centre of the section's loop nearest ``near``: the circle fitted through the ends of its segments
    within ``within_mm`` of ``near`` (a fit, so a segment the plane skipped at a vertex does not pull it)."""
    if len(segments) == 0:
        return None
    mid = segments.mean(axis=1)
    keep = np.linalg.norm(mid - near, axis=1) <= within_mm
    if keep.sum() < 3:
        return None
    return fit_circle(segments[keep].reshape(-1, 3))[1]


def centreline(mesh: trimesh.Trimesh, step_mm: float = STEP_MM) -> tuple[np.ndarray, float]:
    """The tube's centre line marched from one end cap to the other through plane sections ``step_mm`` apart
    (each plane normal to the line's direction, extrapolated from the last two centres), and the tube's radius
    from the caps' area. Shapes: (M, 3) points from cap to cap, float."""
    caps = end_caps(mesh)
    if len(caps) != 2:
        raise ValueError(f"a swept cable has two flat end caps; found {len(caps)}")
    a, b = caps
    r = float(np.sqrt((a.area_mm2 + b.area_mm2) / 2 / np.pi))
    pts, d = [a.centre], -a.normal
    # ring_centre keeps the segments whose middles lie within 1.5 r of the plane's origin: they lie on triangles
    # whose boxes meet the cube of that half-side, so the section of those triangles alone is the same
    near = NearFaces(mesh, 1.5 * r, 20 * step_mm)
    for _ in range(100000):
        q = pts[-1] + step_mm * d
        # the next section would reach the far cap's plane, at the far cap (a route may start beyond that plane
        # and come back to it: the power leads into the switch's tabs and the converter's rear end)
        if (q - b.centre) @ b.normal > -step_mm / 2 and np.linalg.norm(q - b.centre) < 2 * r + step_mm:
            break
        c = ring_centre(plane_cut(mesh, q, d, near(q)), q, 1.5 * r)
        if c is None:
            raise ValueError(f"the section {step_mm:g} mm past {np.round(pts[-1], 2).tolist()} finds no tube")
        chord = (c - pts[-1]) / np.linalg.norm(c - pts[-1])
        # the tangent at c: the chord's direction turned on by half the turn between the last two chords (from
        # the measured points only; extrapolating from the last plane's normal feeds its error back and swings)
        d = chord if len(pts) < 2 else 1.5 * chord - 0.5 * (pts[-1] - pts[-2]) / np.linalg.norm(pts[-1] - pts[-2])
        d /= np.linalg.norm(d)
        pts.append(c)
    else:
        raise ValueError("the centre line never reached the other cap")
    pts.append(b.centre)
    return np.asarray(pts), r


# ----------------------------------------------------------------------------- bends and lengths
def circle_through(p: np.ndarray, q: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The circle through each triple of points (K, 3): radii (K,) (inf for a straight triple) and centres (K, 3)."""
    a, b = p - s, q - s
    axb = np.cross(a, b)
    n2 = (axb ** 2).sum(-1)
    num = np.cross((a ** 2).sum(-1)[:, None] * b - (b ** 2).sum(-1)[:, None] * a, axb)
    with np.errstate(divide="ignore", invalid="ignore"):
        c = s + num / (2 * n2[:, None])
        r = np.where(n2 > 1e-18, np.linalg.norm(c - s, axis=1), np.inf)
    return r, c


def fit_circle(points: np.ndarray) -> tuple[float, np.ndarray]:
    """The least-squares circle (Kasa's algebraic fit) through points (K, 3) in their best plane: radius, centre."""
    c0 = points.mean(axis=0)
    _, _, vt = np.linalg.svd(points - c0, full_matrices=False)
    uv = (points - c0) @ vt[:2].T
    A = np.column_stack([2 * uv, np.ones(len(uv))])
    sol, *_ = np.linalg.lstsq(A, (uv ** 2).sum(1), rcond=None)
    r = float(np.sqrt(sol[2] + sol[0] ** 2 + sol[1] ** 2))
    return r, c0 + sol[:2] @ vt[:2]


@dataclass(frozen=True)
class MeshBend:
    radius_mm: float       # the circle fitted to the bend's points
    arc_mm: float          # the length of centre line it was fitted over (the bend's arc less a span at each end)
    centre: np.ndarray     # (3,)


def bends(points: np.ndarray, straight_mm: float, span_mm: float) -> list[MeshBend]:
    """The bends of a centre line (M, 3), from the circle through each point and the points ``span_mm`` either
    side: a bend is a run of points whose circles are under ``straight_mm`` and whose centres stay within
    ``SAME_CENTRE_SHARE`` of the radius of the run's mean centre (one arc; the next bend's centre is a radius or
    more away), fitted by one circle through the run's points whose own circle is within 10 % of the run's
    median (the points whose span reaches past the arc's ends left out). An arc shorter than about two spans
    is not resolved."""
    k = max(1, int(round(span_mm / np.linalg.norm(np.diff(points, axis=0), axis=1).mean())))
    if len(points) <= 2 * k:
        return []
    r, c = circle_through(points[:-2 * k], points[k:-k], points[2 * k:])
    out, run = [], []

    def close():
        if len(run) < 3:
            return
        rr = r[run]
        keep = [i for i in run if abs(r[i] - np.median(rr)) <= 0.1 * np.median(rr)]
        if len(keep) >= 3:
            p = points[[k + i for i in keep]]
            rad, centre = fit_circle(p)
            out.append(MeshBend(rad, polyline_length_mm(p), centre))

    for i in range(len(r)):
        if r[i] < straight_mm and (not run or np.linalg.norm(c[i] - c[run].mean(0)) <= SAME_CENTRE_SHARE * r[i]):
            run.append(i)
            continue
        close()
        run = [i] if r[i] < straight_mm else []
    close()
    return out


def polyline_length_mm(points: np.ndarray) -> float:
    return float(np.linalg.norm(np.diff(points, axis=0), axis=1).sum())


def volume_length_mm(mesh: trimesh.Trimesh) -> float:
    """The tube's length as its volume over its cross-section (the mean of the two caps' tessellated areas, the
    same polygon the sweep carries along)."""
    caps = end_caps(mesh)
    return float(mesh.volume / np.mean([c.area_mm2 for c in caps]))


# ----------------------------------------------------------------------------- inside points and containment
def inside_points(points: np.ndarray, radius: float, share: float = 0.6, trim_mm: float = 0.2) -> np.ndarray:
    """Points strictly inside the tube: each centre-line point (not the caps) and four around it at ``share`` x
    the radius in its section's plane, dropping those within ``trim_mm`` of either end. Shape (K, 3)."""
    t = np.gradient(points, axis=0)
    t /= np.linalg.norm(t, axis=1)[:, None]
    ref = np.where(np.abs(t[:, 2:3]) < 0.9, np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0]))
    u = np.cross(t, ref)
    u /= np.linalg.norm(u, axis=1)[:, None]
    v = np.cross(t, u)
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])
    keep = (s >= trim_mm) & (s <= s[-1] - trim_mm)
    p, u, v = points[keep], u[keep], v[keep]
    rr = share * radius
    return np.concatenate([p, p + rr * u, p - rr * u, p + rr * v, p - rr * v])


def z_boxes(mesh: trimesh.Trimesh) -> TriangleBoxes:
    """The broad phase :func:`contains` casts its rays (along RAY_DIR, nearly z) through: a grid in x and y."""
    return TriangleBoxes(mesh.triangles, axes=(0, 1))


def contains(mesh: trimesh.Trimesh, points: np.ndarray, tree: TriangleBoxes | None = None) -> np.ndarray:
    """Which points (K, 3) are inside the closed mesh: an odd count of crossings along ``RAY_DIR`` (trimesh's
    ray-triangle test with every hit, the grid broad phase). Points outside the mesh's box are outside."""
    lo, hi = mesh.bounds
    out = np.zeros(len(points), bool)
    cand = np.flatnonzero(np.all(points >= lo, axis=1) & np.all(points <= hi, axis=1))
    if len(cand) == 0:
        return out
    tree = tree or z_boxes(mesh)
    dirs = np.tile(RAY_DIR, (len(cand), 1))
    _, ray, _ = ray_triangle_id(mesh.triangles, points[cand], dirs, tree=tree, multiple_hits=True,
                                triangles_normal=mesh.face_normals)
    counts = np.bincount(ray, minlength=len(cand))
    out[cand] = counts % 2 == 1
    return out
