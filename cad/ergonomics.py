"""Ergonomics, measured on the layout and the placed parts (cad/checks.py turns each into a check):

- **grip span**: the clear span between a handle's posts (grip length minus both posts) against
  ``enclosure.ergonomics.min_clear_span_mm``;
- **stands on a table**: the rig set down upright rests on the parts whose lowest points are lowest;
  their contact points' convex hull is the support polygon. Tilted by an angle towards one of the
  hull's edges, the rig tips when its centre of mass passes over that edge: the tipping angle is
  ``atan(distance from the centre of mass to the edge, in plan / its height above the table)``. Every
  edge's angle must reach ``min_tilt_deg``, and no camera may be among the parts it rests on;
- **record button reach**: the distance from the surface of the nearest grip (a cylinder of the
  grip's width around its axis, between its posts) to the button's actuator against
  ``thumb_reach_mm``.

Pure numpy over points; the geometry comes from the caller (rig frame, mm).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: a part resting within this height of the lowest point touches the table
TABLE_CONTACT_MM = 0.5
#: node names of the cameras (the rig must not rest on one)
CAMERA_PREFIXES = ("zed_x", "boson_")


@dataclass(frozen=True)
class Grip:
    """A handle's grip: its axis from ``a`` to ``b`` between the posts (rig frame) and its radius."""
    name: str
    a: tuple[float, float, float]
    b: tuple[float, float, float]
    radius: float


def grips(lay) -> list[Grip]:
    """Every placed handle's grip, between its posts (the part of it a hand holds)."""
    g = lay.handles.geometry
    z = g.post_height + g.grip_d / 2
    half = g.grip_length / 2 - g.post_width
    out = []
    for name, pose in lay.handles.poses.items():
        a, b = pose.apply(np.array([[-half, 0.0, z], [half, 0.0, z]]))
        out.append(Grip(f"handle_{name}", tuple(a), tuple(b), g.grip_d / 2))
    return out


def clear_span_mm(lay) -> float:
    g = lay.handles.geometry
    return g.grip_length - 2 * g.post_width


def distance_to_grip_mm(point, grip: Grip) -> float:
    """From ``point`` to the grip's surface (0 inside it)."""
    p, a, b = (np.asarray(v, float) for v in (point, grip.a, grip.b))
    ab = b - a
    t = np.clip((p - a) @ ab / (ab @ ab), 0.0, 1.0)
    return max(0.0, float(np.linalg.norm(p - (a + t * ab))) - grip.radius)


def convex_hull(points: np.ndarray) -> np.ndarray:
    """(k, 2) the hull of (n, 2) points, counter-clockwise (Andrew's monotone chain)."""
    pts = sorted(set(map(tuple, np.round(points, 6))))
    if len(pts) < 3:
        return np.array(pts)

    def half(seq):
        out: list = []
        for p in seq:
            while len(out) >= 2 and np.cross(np.subtract(out[-1], out[-2]), np.subtract(p, out[-2])) <= 0:
                out.pop()
            out.append(p)
        return out
    lower, upper = half(pts), half(reversed(pts))
    return np.array(lower[:-1] + upper[:-1])


@dataclass(frozen=True)
class TipEdge:
    angle_deg: float        # tilt that tips the rig over this edge (negative: it tips on its own)
    towards: tuple[float, float]   # the edge's outward normal in plan (x, y)
    distance_mm: float      # the centre of mass from the edge in plan (negative: outside)


def tipping_edges(hull: np.ndarray, com: np.ndarray, table_z: float) -> list[TipEdge]:
    """Per support polygon edge (counter-clockwise hull): the tilt that tips the rig over it."""
    h = float(com[2] - table_z)
    out = []
    for i in range(len(hull)):
        p, q = hull[i], hull[(i + 1) % len(hull)]
        e = q - p
        n = np.array([e[1], -e[0]]) / np.linalg.norm(e)          # outward for a counter-clockwise hull
        d = float((p - com[:2]) @ n)
        out.append(TipEdge(math.degrees(math.atan2(d, h)), (float(n[0]), float(n[1])), d))
    return out


def support(bottoms: dict[str, np.ndarray]) -> tuple[float, list[str], np.ndarray]:
    """(table z, the parts resting on it, their contact points (n, 2) in plan) from each part's points."""
    table = min(float(p[:, 2].min()) for p in bottoms.values())
    resting = [n for n, p in bottoms.items() if p[:, 2].min() <= table + TABLE_CONTACT_MM]
    pts = np.vstack([bottoms[n][bottoms[n][:, 2] <= table + TABLE_CONTACT_MM, :2] for n in resting])
    return table, resting, pts


def stability(bottoms: dict[str, np.ndarray], com: np.ndarray, min_tilt_deg: float) -> tuple[bool, list[str], dict]:
    """Whether the rig stands: (ok, problems and details, data)."""
    table, resting, pts = support(bottoms)
    hull = convex_hull(pts)
    lines = []
    if len(hull) < 3:
        return False, [f"the rig rests on a line or a point ({', '.join(resting)}): it falls over"], {}
    edges = tipping_edges(hull, np.asarray(com, float), table)
    worst = min(edges, key=lambda e: e.angle_deg)
    on_camera = [n for n in resting if n.startswith(CAMERA_PREFIXES)]
    if worst.angle_deg < min_tilt_deg:
        lines.append(f"it tips over at {worst.angle_deg:.1f} deg towards ({worst.towards[0]:+.2f}, "
                     f"{worst.towards[1]:+.2f}) (centre of mass {worst.distance_mm:.1f} mm inside the edge of what it "
                     f"stands on, {com[2] - table:.0f} mm up); expected at least {min_tilt_deg:g} deg")
    if on_camera:
        lines.append(f"it rests on a camera: {', '.join(on_camera)}")
    ok = not lines
    lines.append(f"rests on {', '.join(resting)} (table at z {table:.1f} mm); tips over at {worst.angle_deg:.1f} deg "
                 f"at the least (towards ({worst.towards[0]:+.2f}, {worst.towards[1]:+.2f}))")
    forward = [e for e in edges if e.towards[0] > 0.7]
    if forward:
        lines.append(f"forward (towards the cameras): {min(e.angle_deg for e in forward):.1f} deg")
    return ok, lines, {"min_tilt_deg": worst.angle_deg, "resting_on": resting,
                       "support_polygon_mm": hull.round(2).tolist(), "table_z_mm": table}
