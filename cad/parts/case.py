"""The case: one shell around everything, split on a horizontal plane into a lower tray and a lid.

Why this split (docs/cad.md has the long form): the plane sits just under the ZED X, so the camera's
166 mm window and the Orin's 110 mm port window are notches open at the split edge instead of bridges
far longer than the printer's ``max_bridge_mm``; the tray prints on its floor and the lid on its roof,
both without support. Lugs with 45 degree gussets outside the walls carry the split's screws and
inserts, so nothing of the joint reaches into the crowded interior. Pads outside the lid hold the
handles' inserts for the same reason.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import cadquery as cq
import numpy as np

from ..layout import Hole, Layout, fov_half_angles_deg
from ..layout.case import front_ledge_chamfer, lug_spot_face
from ..layout.constants import HOLE_LEAD_MM
from ..geom import Bounds
from ..solids import box, cylinder, moved
from .common import PrintSetup, hole_tools


#: a boss on the floor starts this far inside the floor, so the two fuse into one solid
BOSS_FUSE_MM = 0.5


@dataclass(frozen=True)
class ConeCut:
    apex: tuple[float, float, float]
    axis: tuple[float, float, float]
    half_angle_deg: float
    length: float
    min_diameter: float


@dataclass(frozen=True)
class CaseSpec:
    outer: Bounds
    wall: float
    radius: float
    split_z: float
    lug_width: float
    lug_protrusion: float
    lower_lug_mm: float
    lid_lug_mm: float
    lugs: tuple[tuple[float, float], ...]
    pads: tuple[Bounds, ...]
    bosses: tuple[tuple[float, float, float, float, float], ...]   # (x, y, z0, diameter, height): on the floor
    boxes: tuple[Bounds, ...]                      # box cut-outs (windows, notches, vents)
    cones: tuple[ConeCut, ...]                     # camera windows
    panel_cuts: tuple[tuple[object, tuple], ...]   # (PanelPart, pose matrix rows)
    holes: tuple[Hole, ...]
    #: 45 deg chamfers under the roof behind the front wall: (x of the front's inner face, z of the roof's
    #: inner face, size, y0, y1), so the lid's front ledge prints (cad/layout/case.py front_ledge_chamfer)
    chamfers: tuple[tuple[float, float, float, float, float], ...] = ()

    def build_shell(self) -> cq.Shape:
        o, w = self.outer, self.wall
        outer = cq.Workplane().add(box(o))
        if self.radius > 0:
            outer = outer.edges("|Z").fillet(self.radius)
        inner_b = o.grown(-w)
        inner = cq.Workplane().add(box(inner_b))
        if self.radius - w > 0.2:
            inner = inner.edges("|Z").fillet(self.radius - w)
        shell = outer.val().cut(inner.val())
        adds = [self._lug(x, s, lower) for x, s in self.lugs for lower in (True, False)]
        adds += [box(p) for p in self.pads]
        adds += [cylinder(d, h + BOSS_FUSE_MM, (x, y, z0 - BOSS_FUSE_MM)) for x, y, z0, d, h in self.bosses]
        adds += [self._chamfer(*ch) for ch in self.chamfers]
        shell = shell.fuse(*adds).clean()
        return shell.cut(*self._cutters()).clean()

    @staticmethod
    def _chamfer(x: float, z: float, size: float, y0: float, y1: float) -> cq.Shape:
        """A 45 deg wedge in the corner of the front wall's inner face (x) and the roof's (z), running
        ``BOSS_FUSE_MM`` into both so they fuse."""
        f = BOSS_FUSE_MM
        pts = [cq.Vector(x + f, y0, z + f), cq.Vector(x + f, y0, z - size), cq.Vector(x - size, y0, z + f)]
        face = cq.Face.makeFromWires(cq.Wire.makePolygon(pts, close=True))
        return cq.Solid.extrudeLinear(face, cq.Vector(0, y1 - y0, 0))

    def _lug(self, x: float, s: float, lower: bool) -> cq.Shape:
        o, p, w = self.outer, self.lug_protrusion, self.lug_width
        y_wall = o.hi[1] if s > 0 else o.lo[1]
        t = self.lower_lug_mm if lower else self.lid_lug_mm
        z0 = self.split_z - t if lower else self.split_z
        # profile in the y-z plane: the block and its 45 degree gusset towards the wall
        ys = [y_wall - s * 0.5, y_wall + s * p]
        if lower:
            pts = [(ys[0], z0 + t), (ys[1], z0 + t), (ys[1], z0), (y_wall, z0 - p), (ys[0], z0 - p)]
        else:
            pts = [(ys[0], z0), (ys[1], z0), (ys[1], z0 + t), (y_wall, z0 + t + p), (ys[0], z0 + t + p)]
        wp = cq.Workplane("YZ", origin=(x - w / 2, 0, 0)).polyline(pts).close().extrude(w)
        return wp.val()

    def _cutters(self) -> list[cq.Shape]:
        tools = [box(b) for b in self.boxes]
        for c in self.cones:
            # radius where the cone leaves the wall's outer face (the cut runs 1 mm past it)
            r1 = max((c.length - 1.0) * math.tan(math.radians(c.half_angle_deg)), c.min_diameter / 2)
            # a straight hole as wide as the cone where it leaves the wall: no feathered edge inside
            tools.append(cylinder(2 * r1, c.length, c.apex, c.axis))
        from platform_tools.rig.frames import Pose
        for part, rows in self.panel_cuts:
            M = np.array(rows)
            tools.append(moved(part.cutout(margin=0.25, depth=self.wall + 1.0), Pose.from_matrix(M)))
        tools += hole_tools(self.holes)
        return tools

    def build(self, half: str) -> cq.Shape:
        shell = self.build_shell()
        o = self.outer
        big = 2 * max(o.size) + 100
        if half == "lower":
            keep = Bounds((o.lo[0] - big, o.lo[1] - big, o.lo[2] - big), (o.hi[0] + big, o.hi[1] + big, self.split_z))
        else:
            keep = Bounds((o.lo[0] - big, o.lo[1] - big, self.split_z), (o.hi[0] + big, o.hi[1] + big, o.hi[2] + big))
        return shell.intersect(box(keep)).clean()


@dataclass(frozen=True)
class CaseHalf:
    """One half of the case (its cache key is the whole spec: both halves share the cuts)."""
    part_id: str
    half: str
    spec: CaseSpec

    def build(self) -> cq.Shape:
        return self.spec.build(self.half)


def case_spec(lay: Layout) -> CaseSpec:
    c = lay.c
    boxes = [lay.case.port_cutout] + list(lay.case.vents)
    # the ZED X window: a notch in the lid from the split plane to above the camera
    z = lay.cameras.zed_box
    r_in = max(lay.rig.desc.enclosure.corner_radius_mm - lay.fits.wall, 0.0)   # past the inner corner fillet
    # across the whole front (corners too): a notch side inside the corner radius left a knife edge between
    # it and the rounded face (0.21 mm at 0.1 mm from the edge: the wall check); the side walls end on a
    # flat face before the radius begins
    o = lay.case.outer
    boxes.append(Bounds((o.hi[0] - lay.fits.wall - r_in - 1.0, min(z.lo[1] - lay.fits.clear, o.lo[1] - 1.0), lay.case.split_z - 0.01),
                        (o.hi[0] + 1.0, max(z.hi[1] + lay.fits.clear, o.hi[1] + 1.0), z.hi[2] + lay.fits.clear)))
    boxes += [lug_spot_face(lay.case, c, x, s) for x, s in lay.case.lugs]
    half = fov_half_angles_deg(lay.rig)["thermal"][0] + c.fov_margin_deg
    cones = []
    for t in lay.cameras.thermal.values():
        apex = tuple(t.pose.t)
        axis = tuple(t.pose.rotate(np.array([1.0, 0, 0])))
        length = (lay.case.outer.hi[0] - apex[0]) / max(axis[0], 1e-6) + 1.0
        cones.append(ConeCut(apex, axis, half, length, lay.cameras.lens.diameter_mm + 2 * lay.fits.clear))
    panel = tuple((part, tuple(map(tuple, pose.matrix()))) for part, pose in lay.controls.values())
    holes = lay.holes_for("case_lower") + lay.holes_for("case_lid")
    # the cable gland's hole through the floor, the gland table's diameter
    (gx, gy, gz), gd = lay.power.gland_hole
    holes += (Hole("case_lower", (gx, gy, gz - HOLE_LEAD_MM), (0.0, 0.0, 1.0), gd, lay.fits.wall + 2 * HOLE_LEAD_MM),)
    floor = lay.case.interior.lo[2]
    bosses = tuple((x, y, floor, d, h) for x, y, d, h in lay.power.floor_bosses)
    i = lay.case.interior
    ch = front_ledge_chamfer(lay.rig, lay.fits, lay.case, lay.cameras)
    chamfers = ((i.hi[0], i.hi[2], ch, i.lo[1], i.hi[1]),) if ch > 0 else ()
    return CaseSpec(lay.case.outer, lay.fits.wall, lay.rig.desc.enclosure.corner_radius_mm, lay.case.split_z, c.lug_width_mm,
                    c.lug_protrusion_mm, lay.fits.insert_plate_mm, c.lid_lug_mm, tuple(lay.case.lugs),
                    tuple(lay.handles.pads), bosses, tuple(boxes), tuple(cones), panel, holes, chamfers)


PRINT = {
    "case_lower": PrintSetup((0.0, 0.0, 0.0), "on its floor: walls, lugs with 45 deg gussets, notches open upwards"),
    "case_lid": PrintSetup((0.0, -90.0, 0.0), "on its rear face: roof and walls stand up, the ZED X notch and the "
                                              "lugs' 45 deg gussets face up; upside down the roof floated 4.8 mm on "
                                              "the handle pads (the overhang check)"),
}
