"""Small geometry helpers shared by the part builders: boxes by their bounds, poses as CadQuery
locations, shapes moved by a :class:`~platform_tools.rig.frames.Pose`.

Every builder works in millimetres in its part's own frame (x forward, y left, z up, as the rig).
"""
from __future__ import annotations

from dataclasses import dataclass

import cadquery as cq
import numpy as np
from OCP.gp import gp_Trsf

from platform_tools.rig.frames import Pose

Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class Bounds:
    """An axis-aligned box by its minimum and maximum corners (mm)."""
    lo: Vec3
    hi: Vec3

    def __post_init__(self) -> None:
        if any(h <= l for l, h in zip(self.lo, self.hi)):
            raise ValueError(f"empty bounds {self.lo} .. {self.hi}")

    @classmethod
    def centred(cls, centre: Vec3, size: Vec3) -> "Bounds":
        return cls(tuple(c - s / 2 for c, s in zip(centre, size)), tuple(c + s / 2 for c, s in zip(centre, size)))

    @property
    def size(self) -> Vec3:
        return tuple(h - l for l, h in zip(self.lo, self.hi))

    @property
    def centre(self) -> Vec3:
        return tuple((h + l) / 2 for l, h in zip(self.lo, self.hi))

    def grown(self, d: float) -> "Bounds":
        return Bounds(tuple(v - d for v in self.lo), tuple(v + d for v in self.hi))

    def overlaps(self, other: "Bounds", eps: float = 0.0) -> bool:
        return all(a_lo < b_hi - eps and b_lo < a_hi - eps
                   for a_lo, a_hi, b_lo, b_hi in zip(self.lo, self.hi, other.lo, other.hi))

    def gap_to(self, other: "Bounds") -> float:
        """Largest axis gap between two boxes (negative when they overlap on every axis)."""
        return max(max(b_lo - a_hi, a_lo - b_hi) for a_lo, a_hi, b_lo, b_hi
                   in zip(self.lo, self.hi, other.lo, other.hi))

    def solid(self) -> cq.Shape:
        return box(self)


def box(b: Bounds) -> cq.Shape:
    (x0, y0, z0), (x1, y1, z1) = b.lo, b.hi
    return cq.Solid.makeBox(x1 - x0, y1 - y0, z1 - z0, cq.Vector(x0, y0, z0))


def cylinder(d: float, length: float, base: Vec3 = (0, 0, 0), axis: Vec3 = (0, 0, 1)) -> cq.Shape:
    return cq.Solid.makeCylinder(d / 2, length, cq.Vector(*base), cq.Vector(*axis))


def cone(d0: float, d1: float, length: float, base: Vec3 = (0, 0, 0), axis: Vec3 = (0, 0, 1)) -> cq.Shape:
    return cq.Solid.makeCone(d0 / 2, d1 / 2, length, cq.Vector(*base), cq.Vector(*axis))


def tube(od: float, id_: float, length: float, base: Vec3 = (0, 0, 0), axis: Vec3 = (0, 0, 1)) -> cq.Shape:
    return cylinder(od, length, base, axis).cut(cylinder(id_, length, base, axis))


def fuse_all(shapes) -> cq.Shape:
    shapes = list(shapes)
    if len(shapes) == 1:
        return shapes[0]
    return shapes[0].fuse(*shapes[1:]).clean()


def cut_all(shape: cq.Shape, tools) -> cq.Shape:
    tools = list(tools)
    if not tools:
        return shape
    return shape.cut(*tools).clean()


def one_solid(shape: cq.Shape) -> cq.Shape:
    """The shape as a single solid (builders must not leave loose pieces)."""
    solids = shape.Solids()
    if len(solids) != 1:
        raise ValueError(f"expected one solid, the builder made {len(solids)}")
    return solids[0]


def trsf(pose: Pose) -> gp_Trsf:
    M = pose.matrix()
    t = gp_Trsf()
    t.SetValues(*M[0, :4], *M[1, :4], *M[2, :4])
    return t


def location(pose: Pose) -> cq.Location:
    return cq.Location(trsf(pose))


def moved(shape: cq.Shape, pose: Pose) -> cq.Shape:
    """A copy of ``shape`` (in its own frame) placed by ``pose`` (its frame in the target frame)."""
    return shape.moved(location(pose))


#: an overlap of two solids below this is a touch (faces that meet), not a clash (mm^3)
TOUCH_MM3 = 0.01


def common_volume_mm3(a: cq.Shape, b: cq.Shape) -> float:
    """The volume two shapes share (mm^3): their intersection's, 0 when it holds no solid."""
    c = a.intersect(b)
    return c.Volume() if c.Solids() else 0.0


def bounds_of(shape: cq.Shape, pose: Pose | None = None) -> Bounds:
    """The tight box of a shape (exact surfaces, not their triangulation)."""
    from OCP.Bnd import Bnd_Box
    from OCP.BRepBndLib import BRepBndLib
    s = moved(shape, pose) if pose is not None else shape
    b = Bnd_Box()
    BRepBndLib.AddOptimal_s(s.wrapped, b, False, False)
    x0, y0, z0, x1, y1, z1 = b.Get()
    return Bounds((x0, y0, z0), (x1, y1, z1))


def placed_bounds(local: Bounds, pose: Pose) -> Bounds:
    """The axis-aligned box (rig frame, mm) around ``local`` (a box in a part's frame) placed at ``pose``."""
    corners = np.array([[x, y, z] for x in (local.lo[0], local.hi[0]) for y in (local.lo[1], local.hi[1])
                        for z in (local.lo[2], local.hi[2])])
    p = pose.apply(corners)
    return Bounds(tuple(p.min(axis=0)), tuple(p.max(axis=0)))


def pose_xyz(x: float, y: float, z: float, rpy_deg: Vec3 = (0.0, 0.0, 0.0)) -> Pose:
    return Pose.from_xyz_rpy_deg((x, y, z), rpy_deg)


def pose_axis_z_to(direction: Vec3, origin: Vec3) -> Pose:
    """A pose whose z axis points along ``direction`` (a unit axis vector), placed at ``origin``."""
    d = np.asarray(direction, dtype=float)
    d /= np.linalg.norm(d)
    ref = np.array([1.0, 0, 0]) if abs(d[0]) < 0.9 else np.array([0, 1.0, 0])
    x = np.cross(ref, d)
    x /= np.linalg.norm(x)
    y = np.cross(d, x)
    return Pose(np.column_stack([x, y, d]), np.asarray(origin, dtype=float))
