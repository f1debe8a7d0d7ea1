"""Two checks seen from the exported meshes (tests only): independent paths beside ``cad/ergonomics.py`` with
``check_stands`` (the rig on a table) and ``cad/assembly_order.py`` ``driver_paths`` (each screw's driver).

They share no code with the checks: what they read of the rig is data (the assembly's nodes, their poses and
shapes as exported STL, the joints' head points and axes, the rig's part masses and densities, the guide's
``steps.yaml``, the fastener table's driver sizes, the check's seat gap constant); the rest is numpy, scipy
(``ConvexHull``) and trimesh (the STL, ``center_mass``, its ray caster with the numpy broad phase of
``tests/cad/trimesh_rays.py``: no rtree or boolean backend on this machine).
"""
from __future__ import annotations

import fnmatch
import math
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh
import yaml
from scipy.spatial import ConvexHull

from tests.cad.trimesh_rays import ray_hits

REPO = Path(__file__).resolve().parents[2]
#: the parts' STL as the exports write them (cad/export.py's default tolerances)
PART_TOLERANCE_MM, PART_ANGULAR_RAD = 0.1, 0.2
#: the guide's steps and the fastener table (read as data)
STEPS_YAML = REPO / "docs" / "assembly" / "steps.yaml"
FASTENERS_YAML = REPO / "cad" / "bought" / "fasteners.yaml"

_MESHES: dict[int, dict[str, trimesh.Trimesh]] = {}


def node_meshes(asm) -> dict[str, trimesh.Trimesh]:
    """Every node's shape exported to STL (rig frame, as placed) and read back by trimesh; once per assembly
    (about 9 s for the 130 nodes)."""
    if id(asm) not in _MESHES:
        import cadquery as cq
        folder = Path(tempfile.mkdtemp(prefix="mesh_paths_"))
        out = {}
        for n in asm.nodes:
            p = folder / f"{n.name}.stl"
            cq.exporters.export(n.shape(asm.cache), str(p), "STL", tolerance=PART_TOLERANCE_MM,
                                angularTolerance=PART_ANGULAR_RAD)
            out[n.name] = trimesh.load(str(p))
        _MESHES[id(asm)] = out
    return _MESHES[id(asm)]


# ----------------------------------------------------------------------------- standing on a table
def part_masses_g(asm, meshes) -> dict[str, float]:
    """Each node's mass (g), from the rig's data: a bought part's or fastener's ``mass_g`` (config/rig.yaml); a
    printed part the mesh's volume times the filament's density, the machined heat sinks times theirs."""
    rig = asm.rig
    out = {}
    for n in asm.nodes:
        if n.category == "printed":
            out[n.name] = meshes[n.name].volume / 1000 * rig.desc.printing.printer.density_g_cm3
        elif n.category == "machined":
            out[n.name] = meshes[n.name].volume / 1000 * rig.desc.enclosure.heat_sink.density_g_cm3
        else:
            out[n.name] = rig.part(n.part_id).mass_g.value
    return out


@dataclass(frozen=True)
class Standing:
    table_z: float
    resting_on: list[str]       # the nodes with a vertex on the table
    hull: np.ndarray            # (k, 2) the support polygon's corners
    com: np.ndarray             # (3,)
    edge_mm: float              # the centre of mass's plan distance to the polygon's nearest edge (< 0 outside)
    min_tilt_deg: float         # atan(edge_mm / height of the centre of mass above the table)


def standing(meshes: dict[str, trimesh.Trimesh], masses: dict[str, float], contact_mm: float,
             extra=()) -> Standing:
    """The rig set down as it is placed (rig frame, z up) on a table at its lowest vertex: the support polygon is
    the 2D convex hull of every vertex within ``contact_mm`` of that; the centre of mass is the part masses at
    their meshes' centroids (``center_mass``: each part's mass spread uniformly through its modelled solid), plus
    ``extra`` point masses (name, g, point)."""
    table = min(float(m.vertices[:, 2].min()) for m in meshes.values())
    low = {k: m.vertices[m.vertices[:, 2] <= table + contact_mm, :2] for k, m in meshes.items()}
    resting = sorted(k for k, v in low.items() if len(v))
    hull = ConvexHull(np.vstack([low[k] for k in resting]))
    m = sum(masses.values()) + sum(g for _, g, _ in extra)
    com = (sum(masses[k] * np.asarray(meshes[k].center_mass) for k in meshes)
           + sum((g * np.asarray(p, float) for _, g, p in extra), np.zeros(3))) / m
    # scipy's facets: normal . x + offset <= 0 inside, |normal| = 1; the distance inside is -(normal . x + offset)
    edge = float(np.min(-(hull.equations[:, :2] @ com[:2] + hull.equations[:, 2])))
    return Standing(table, resting, hull.points[hull.vertices], com, edge,
                    math.degrees(math.atan2(edge, com[2] - table)))


# ----------------------------------------------------------------------------- driver paths
def guide_steps(names: list[str], path: Path = STEPS_YAML) -> list[tuple[str, list[str], bool]]:
    """(id, nodes, bench) per step of the guide: a node belongs to the first step (in order, then the first of
    its patterns) that matches it."""
    claimed: set[str] = set()
    out = []
    for s in yaml.safe_load(path.read_text())["steps"]:
        nodes = []
        for pat in s.get("nodes") or ():
            for n in names:
                if n not in claimed and fnmatch.fnmatchcase(n, pat):
                    claimed.add(n)
                    nodes.append(n)
        out.append((s["id"], nodes, bool(s.get("bench"))))
    return out


def drivers(path: Path = FASTENERS_YAML) -> dict[str, dict]:
    """The fastener table's driver envelope per thread (bit and handle diameters and lengths, mm)."""
    return {t: row["driver"] for t, row in yaml.safe_load(path.read_text())["sizes"].items()}


@dataclass(frozen=True)
class DriverPath:
    screw: str
    step: str
    blocked_by: list[str]      # installed nodes met inside the envelope, nearest first
    nearest_mm: float          # the nearest such point, out from the head's top face (inf: clear)
    along_mm: dict             # per part in the way, its nearest point out from the head's top face


def _rings(radius: float, rim_in_mm: float, rings=(0.0, 0.5, 1.0), around: int = 24) -> np.ndarray:
    """(n, 2) points on the disc: its centre, and rings at the given shares of the radius (the outermost
    ``rim_in_mm`` inside the rim, so a part touching the envelope's surface is not counted)."""
    pts = []
    for s in rings:
        r = min(s * radius, radius - rim_in_mm)
        if r <= 0:
            pts.append((0.0, 0.0))
            continue
        a = np.linspace(0, 2 * np.pi, around, endpoint=False)
        pts += list(zip(r * np.cos(a), r * np.sin(a)))
    return np.array(pts)


def driver_paths_on_meshes(asm, meshes, steps, seat_gap_mm: float, rim_in_mm: float = 0.05,
                           only=None) -> dict[str, DriverPath]:
    """Each screw's driver at its step: a bit then a handle (cylinders along the axis out from the head's top
    face, ``seat_gap_mm`` clear of it), against the installed parts' meshes (every part of the steps up to and
    including the screw's, or only its own step's for a ``bench`` step). A part blocks the driver when

    - a ray along the axis from the envelope's start (its centre and rings out to its rim) hits the part's
      triangles within the envelope's length (a face across the path: its vertices can all lie outside), or
    - a ray starts inside the part (an odd count of crossings along it: a part across the plane where the
      bit or the handle begins), or
    - one of the part's vertices lies inside the envelope (``rim_in_mm`` in from its surface: a small part
      the rays pass by).

    The head's top face is the screw mesh's furthest vertex out along the axis (the joint gives the axis).
    ``only``: the screws to look at (default: every joint's)."""
    table = drivers()
    joints = {f"screw_{j.name}": j for j in asm.layout.joints}
    step_of = {n: i for i, (_, nodes, _) in enumerate(steps) for n in nodes}
    out = {}
    for screw, j in joints.items():
        if only is not None and screw not in only:
            continue
        i = step_of[screw]
        sid, _, bench = steps[i]
        installed = [n for k, (_, nodes, _) in enumerate(steps) if (k == i if bench else k <= i) for n in nodes
                     if n != screw]
        d = table[j.thread]
        axis = -np.asarray(j.direction, float)
        head = np.asarray(j.head, float)
        top = head + float(((meshes[screw].vertices - head) @ axis).max()) * axis
        start = top + seat_gap_mm * axis
        u = np.cross(axis, [1.0, 0, 0] if abs(axis[0]) < 0.9 else [0, 1.0, 0])
        u /= np.linalg.norm(u)
        v = np.cross(axis, u)
        segs = [(d["bit_diameter_mm"] / 2, 0.0, d["bit_length_mm"]),
                (d["handle_diameter_mm"] / 2, d["bit_length_mm"], d["bit_length_mm"] + d["handle_length_mm"])]
        total = segs[-1][2]
        reach = max(r for r, _, _ in segs)
        hits: dict[str, float] = {}
        for other in installed:
            m = meshes[other]
            rel = m.vertices - start
            along = rel @ axis
            radial = np.linalg.norm(rel - np.outer(along, axis), axis=1)
            # the broad phase: a part with no triangle whose box meets the envelope's box stays out of it
            lo = np.minimum(start, start + total * axis) - reach
            hi = np.maximum(start, start + total * axis) + reach
            faces = np.flatnonzero(np.all(m.triangles.min(axis=1) <= hi, axis=1)
                                   & np.all(m.triangles.max(axis=1) >= lo, axis=1))
            if not len(faces):
                continue
            best = math.inf
            for r, a0, a1 in segs:
                inside = (along > a0 + rim_in_mm) & (along < a1) & (radial < r - rim_in_mm)
                if inside.any():
                    best = min(best, float(along[inside].min()))
                disc = _rings(r, rim_in_mm)
                origins = start + a0 * axis + disc[:, :1] * u + disc[:, 1:] * v
                # the part's triangles in the column the rays sweep out to beyond any part (the parity below
                # needs the crossings past the envelope's end too)
                col_lo = np.minimum(start, start + 1e4 * axis) - r
                col_hi = np.maximum(start, start + 1e4 * axis) + r
                col = np.flatnonzero(np.all(m.triangles.min(axis=1) <= col_hi, axis=1)
                                     & np.all(m.triangles.max(axis=1) >= col_lo, axis=1))
                if not len(col):
                    continue
                tri, ray, loc = ray_hits(m.triangles[col], m.face_normals[col], origins,
                                         np.tile(axis, (len(origins), 1)))
                t = (np.asarray(loc, float).reshape(-1, 3) - start) @ axis
                ray = np.asarray(ray, int)
                within = (t > a0 + rim_in_mm) & (t < a1)
                if within.any():
                    best = min(best, float(t[within].min()))
                # a ray that starts inside the part (an odd count of distinct crossings out along it; the part's
                # mesh is closed): the part is in the way from the segment's start on
                for k in np.unique(ray):
                    if len(np.unique(np.round(t[(ray == k) & (t > a0)], 4))) % 2:
                        best = min(best, a0)
            if best < math.inf:
                hits[other] = best + seat_gap_mm      # from the head's top face
        order = sorted(hits, key=hits.get)
        out[screw] = DriverPath(screw, sid, order, hits[order[0]] if order else math.inf, hits)
    return out
