"""CadQuery solids from the numbers of cad/geom.py: boxes by their bounds, cylinders, cones and tubes, poses as
OpenCascade transforms and locations, shapes moved by a :class:`~platform_tools.rig.frames.Pose`, the volume two
shapes share and a shape's tight box.

Importing it loads CadQuery and OpenCascade; the layout (cad/layout/) and cad/geom.py do not.
Every builder works in millimetres in its part's own frame (x forward, y left, z up, as the rig).
"""
from __future__ import annotations

import cadquery as cq
from OCP.gp import gp_Trsf

from platform_tools.rig.frames import Pose

from cad.geom import Bounds, Vec3


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
