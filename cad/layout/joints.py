"""Every screw joint of the rig: where each screw goes, what it clamps, what its thread engages (a
heat-set insert, a tapped hole in a bought or machined part, a self-tapping pilot hole), its stock
length, and the holes it needs in every part it passes. Rig frame, mm."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from platform_tools.rig import Rig
from platform_tools.rig.frames import Pose

from cad.bought.fasteners import Insert, Screw, fastener_table, pick_length
from cad.geom import Vec3, placed_bounds, pose_axis_z_to

from .cameras import Cameras
from .case import Case, lug_screw_point
from .compute import Compute
from .constants import HOLE_LEAD_MM, Constants
from .cooling import Cooling
from .fits import Fits
from .handles import Handles
from .mounts import CameraMounts
from .power import Power
from .screws import FAN_SCREW_THREAD, fan_screw, zed_mount_thread, zed_screw

#: an insert's screw engages at least this fraction of the insert's length ...
INSERT_MIN_ENGAGEMENT = 0.5
#: ... and stops this short of the insert hole's bottom (a 2 mm stock step always fits this window)
INSERT_BOTTOM_CLEARANCE_MM = 0.1
#: a tapped hole's screw engages at least this fraction of the hole (when that is under the design minimum)
TAPPED_MIN_ENGAGEMENT = 0.6
#: a tap drill we cut ourselves (its diameter is the fastener table's) runs this far past the thread
TAP_DRILL_RUNOUT_MM = 0.5
#: the lug's counterbore runs this far past the lug's gusset
COUNTERBORE_OVERRUN_MM = 1.0
#: the two heat sink screws, across the camera (y), centred under the Boson
HEAT_SINK_SCREW_SPACING_MM = 12.0
#: the heat sink's tapped holes stop this short of the copper base's top (the sleeve's floor)
HEAT_SINK_HOLE_FLOOR_MM = 1.0
#: the ZED foot's floor screws sit this far in from the foot's ends
ZED_FOOT_SCREW_INSET_MM = 5.0
#: a fan screw bites at least this far into its plate, and stops this short of the plate's far face
FAN_SCREW_MIN_ENGAGEMENT_MM = 2.5
FAN_SCREW_TIP_CLEARANCE_MM = 0.4
#: the dock adapter's screw positions, in from its ends (x) and sides (y) (estimates: measure a real adapter)
BATTERY_SCREW_INSET_MM = (10.0, 8.0)

DOWN, UP = (0.0, 0.0, -1.0), (0.0, 0.0, 1.0)


@dataclass(frozen=True)
class Hole:
    """A hole a printed (or machined) part gets: from ``origin`` along ``direction`` (a unit vector),
    ``diameter`` across and ``depth`` deep (mm, rig frame unless a part says otherwise)."""
    part: str
    origin: Vec3
    direction: Vec3
    diameter: float
    depth: float


@dataclass(frozen=True)
class Joint:
    """One screw and what it holds: the screw's head sits at ``head`` and its shank runs along
    ``direction`` (a unit vector) through ``grip_mm`` of clamped parts into ``host`` (an insert, a
    tapped hole in a bought or machined part, or a self-tapping pilot hole). Rig frame, mm."""
    name: str
    screw: Screw               # the bought screw, its stock length picked for this joint
    head: Vec3
    direction: Vec3
    grip_mm: float
    kind: str                  # "insert" | "tapped" | "self_tap"
    host: str                  # node name the thread engages
    holes: tuple[Hole, ...]
    insert: Insert | None = None   # the heat-set insert, when kind == "insert"

    @property
    def screw_id(self) -> str:
        return self.screw.part_id

    @property
    def thread(self) -> str:
        return self.screw.thread

    @property
    def length_mm(self) -> float:
        return self.screw.length_mm

    @property
    def diameter_mm(self) -> float:
        return self.screw.diameter_mm

    @property
    def engagement_mm(self) -> float:
        return self.length_mm - self.grip_mm

    def point(self, along_mm: float) -> Vec3:
        return tuple(np.asarray(self.head) + along_mm * np.asarray(self.direction))

    def pose(self) -> Pose:
        """The screw's frame: z axis back along the shank (head up)."""
        return pose_axis_z_to(tuple(-v for v in self.direction), self.head)

    def insert_pose(self) -> Pose:
        return pose_axis_z_to(tuple(-v for v in self.direction), self.point(self.grip_mm))


class _Joints:
    """Builds the joint list (the only mutable thing here, private to :func:`place_joints`)."""

    def __init__(self, rig: Rig, c: Constants, fits: Fits):
        self.rig, self.c, self.fits = rig, c, fits
        self.screw = rig.desc.enclosure.screw
        self.out: list[Joint] = []

    def insert(self, name, head, direction, grip, clamped: list[str], host: str, extra: tuple[Hole, ...] = ()):
        ins = self.fits.insert
        thread = ins.thread
        length = pick_length(grip, ins.length_mm * INSERT_MIN_ENGAGEMENT, ins.hole_depth_mm - INSERT_BOTTOM_CLEARANCE_MM)
        hd, dvec = np.asarray(head), np.asarray(direction)
        clr = self.fits.screw_hole_mm(thread)
        holes = tuple(Hole(p, tuple(hd - HOLE_LEAD_MM * dvec), direction, clr, grip + 2 * HOLE_LEAD_MM) for p in clamped)
        holes += (Hole(host, tuple(hd + grip * dvec - HOLE_LEAD_MM * dvec), direction, ins.hole_diameter_mm,
                       ins.hole_depth_mm + HOLE_LEAD_MM),)
        self.out.append(Joint(name=name, screw=Screw.from_rig(self.rig, self.screw, thread, length), head=head,
                              direction=direction, grip_mm=grip, kind="insert", host=host, holes=holes + extra,
                              insert=ins))

    def tapped(self, name, screw_id, thread, head, direction, grip, clamped, host, depth, cut_host=None,
               extra: tuple[Hole, ...] = ()):
        length = pick_length(grip, min(self.c.tapped_engagement_min_mm, depth * TAPPED_MIN_ENGAGEMENT), depth)
        hd, dvec = np.asarray(head), np.asarray(direction)
        hole_d = self.fits.screw_hole_mm(thread)
        holes = tuple(Hole(p, tuple(hd - HOLE_LEAD_MM * dvec), direction, hole_d, grip + 2 * HOLE_LEAD_MM)
                      for p in clamped)
        if cut_host:  # a tapped hole we machine ourselves: tap drill
            holes += (Hole(cut_host, tuple(hd + grip * dvec - HOLE_LEAD_MM * dvec), direction,
                           fastener_table().size(thread).tap_drill_mm, depth + TAP_DRILL_RUNOUT_MM),)
        self.out.append(Joint(name=name, screw=Screw.from_rig(self.rig, screw_id, thread, length), head=head,
                              direction=direction, grip_mm=grip, kind="tapped", host=host, holes=holes + extra))


def place_joints(rig: Rig, c: Constants, fits: Fits, *, cameras: Cameras, cooling: Cooling, mounts: CameraMounts,
                 compute: Compute, power: Power, case: Case, handles: Handles) -> tuple[Joint, ...]:
    """Every joint, in assembly order: case split, handles, thermal bar, heat sinks, ZED mount and
    camera, fans, Orin, capture card, battery dock, converter, cut-off, fuse holder."""
    e = rig.desc.enclosure
    j = _Joints(rig, c, fits)
    wall, fo = fits.wall, case.outer.lo[2]
    case_thread = fits.insert.thread          # the case screw's thread
    # case split: lid lug screwed down into an insert in the lower lug, its head in a counterbore
    head_d = rig.dim(e.screw, "head_diameter_mm") + 2 * rig.desc.printing.fits.loose_mm
    for k, (x, s) in enumerate(case.lugs):
        px, py, pz = lug_screw_point(case, c, x, s)
        head = (px, py, pz + c.lid_lug_mm)
        j.insert(f"lug_{k}", head, DOWN, c.lid_lug_mm, ["case_lid"], "case_lower",
                 extra=(Hole("case_lid", head, UP, head_d, c.lug_protrusion_mm + COUNTERBORE_OVERRUN_MM),))
    # handles: two screws per foot into inserts in the pads
    g = handles.geometry
    for hname, pose in handles.poses.items():
        for k, hx in enumerate(g.foot_screw_x()):
            head = tuple(pose.apply(np.array([hx, 0.0, g.foot])))
            d = tuple(pose.rotate(np.array([0.0, 0.0, -1.0])))
            j.insert(f"handle_{hname}_{k}", head, d, g.foot, [f"handle_{hname}"], "case_lid")
    # thermal bar: two screws from under the floor into inserts in the bar
    bar = mounts.thermal_bar
    inner = sorted(abs(t.heat_sink.lo[1]) if t.sign > 0 else abs(t.heat_sink.hi[1]) for t in cameras.thermal.values())[0]
    for k, y in enumerate((bar.centre[1] + inner / 2, bar.centre[1] - inner / 2)):
        j.insert(f"thermal_mount_{k}", (bar.centre[0], y, fo), UP, wall, ["case_lower"], "thermal_mount")
    # heat sinks: two screws from under the floor, through the bar, tapped in the copper base
    half = HEAT_SINK_SCREW_SPACING_MM / 2
    for side, t in cameras.thermal.items():
        cb = placed_bounds(cameras.core.bounds(), t.pose)
        for k, dy in enumerate((-half, half)):
            j.tapped(f"heat_sink_{side}_{k}", e.screw, case_thread, (cb.centre[0], cb.centre[1] + dy, fo), UP,
                     wall + (bar.hi[2] - bar.lo[2]), ["case_lower", "thermal_mount"], f"heat_sink_{side}",
                     c.heat_sink_base_mm - HEAT_SINK_HOLE_FLOOR_MM, cut_host=f"heat_sink_{side}")
    # ZED mount: two floor screws into its foot; the camera on its 1/4-20 thread, its screw passed up
    # through an access hole in the floor under it (wide enough for its head) on its driver
    foot = mounts.zed_foot
    for k, y in enumerate((foot.hi[1] - ZED_FOOT_SCREW_INSET_MM, foot.lo[1] + ZED_FOOT_SCREW_INSET_MM)):
        j.insert(f"zed_mount_{k}", (foot.centre[0], y, fo), UP, wall, ["case_lower"], "zed_mount")
    zm = zed_mount_thread(rig)
    shelf = mounts.zed_shelf
    zs = zed_screw(rig)
    access_d = rig.dim(zs, "head_diameter_mm") + 2 * rig.desc.printing.fits.loose_mm
    for k, pt in enumerate(cameras.zed.mount_points()):
        p = cameras.zed_pose.apply(np.array(pt))
        shelf_t = shelf.hi[2] - shelf.lo[2]
        access = Hole("case_lower", (p[0], p[1], fo - HOLE_LEAD_MM), UP, access_d, wall + 2 * HOLE_LEAD_MM)
        j.tapped(f"zed_x_{k}", zs, zm.thread, (p[0], p[1], p[2] - shelf_t), UP, shelf_t, ["zed_mount"], "zed_x",
                 zm.depth_mm, extra=(access,))
    # fans: self-tapping screws through the fan into its plate; the fan mount's boss screwed to the floor
    fan_screw_id = fan_screw()
    pilot = rig.dim(fan_screw_id, "pilot_hole_diameter_mm")
    fan = cooling.part
    zf = fan.size[2]
    for side, f in cooling.fans.items():
        for k, (u, v) in enumerate(fan.holes()):
            head = tuple(f.pose.apply(np.array([u, v, zf / 2])))
            d = tuple(f.pose.rotate(np.array([0.0, 0.0, -1.0])))
            length = pick_length(zf, FAN_SCREW_MIN_ENGAGEMENT_MM, c.fan_plate_mm - FAN_SCREW_TIP_CLEARANCE_MM)
            hd, dv = np.asarray(head), np.asarray(d)
            holes = (Hole(f"fan_mount_{side}", tuple(hd + zf * dv - HOLE_LEAD_MM * dv), d, pilot,
                          c.fan_plate_mm + 2 * HOLE_LEAD_MM),)
            j.out.append(Joint(name=f"fan_{side}_{k}", screw=Screw.from_rig(rig, fan_screw_id, FAN_SCREW_THREAD, length),
                               head=head, direction=d, grip_mm=zf, kind="self_tap", host=f"fan_mount_{side}",
                               holes=holes))
        boss = cooling.plates[side].boss
        j.insert(f"fan_mount_{side}", (boss.centre[0], boss.centre[1], fo), UP, wall, ["case_lower"], f"fan_mount_{side}")
    # Orin: from under the floor, through a standoff, into the devkit's threads
    orin = compute.orin
    for k, pt in enumerate(orin.mount_points()):
        p = compute.orin_pose.apply(np.array(pt))
        j.tapped(f"orin_{k}", e.screw, case_thread, (p[0], p[1], fo), UP, wall + compute.standoff_h,
                 ["case_lower", f"orin_standoff_{k}"], orin.part_id, orin.mount_depth_mm)
    # capture card: down through each corner hole of its board into the female thread of its standoff
    # (the standoffs' studs are screwed into the devkit's top first: assembly nodes, not joints)
    card, so = compute.card, compute.card_standoff
    card_screw = fastener_table().standoff(card.thread).screw
    for k, pt in enumerate(card.mount_points()):
        p = compute.card_pose.apply(np.array(pt))
        j.tapped(f"card_{k}", card_screw, card.thread, (p[0], p[1], p[2] + card.board_mm), DOWN, card.board_mm, [],
                 f"card_standoff_{k}", so.female_depth_mm)
    # battery dock: from inside the case, through the floor and the battery mount, into the adapter
    bm = power.battery_mount
    ax, ay, _ = power.adapter.size
    ix, iy = BATTERY_SCREW_INSET_MM
    for k, (u, v) in enumerate([(-ax / 2 + ix, ay / 2 - iy), (ax / 2 - ix, ay / 2 - iy),
                                (-ax / 2 + ix, -ay / 2 + iy), (ax / 2 - ix, -ay / 2 + iy)]):
        j.tapped(f"battery_{k}", e.screw, case_thread, (bm.centre[0] + u, v, case.interior.lo[2]), DOWN,
                 wall + (bm.hi[2] - bm.lo[2]), ["case_lower", "battery_mount"], power.adapter.part_id,
                 c.battery_screw_engagement_mm)
    # converter: through the right wall into its base threads
    conv = power.converter
    for k, pt in enumerate(conv.mount_points()):
        p = power.converter_pose.apply(np.array(pt))
        d = tuple(power.converter_pose.rotate(np.array([0.0, 0.0, 1.0])))
        head = tuple(np.asarray(p) - wall * np.asarray(d))
        j.tapped(f"converter_{k}", e.screw, case_thread, head, d, wall, ["case_lower"], conv.part_id, conv.mount_depth_mm)
    # under-voltage cut-off: down through its board into inserts in the floor's bosses (cad/layout/power.py)
    for k, pt in enumerate(power.cutoff.mount_points()):
        p = power.cutoff_pose.apply(np.array(pt))
        j.insert(f"cutoff_{k}", (p[0], p[1], p[2] + power.cutoff.board_mm), DOWN, power.cutoff.board_mm, [], "case_lower")
    # fuse holder: down through each screw tab into an insert in its boss (cad/layout/power.py)
    fuse = power.fuse
    for k, pt in enumerate(fuse.mount_points()):
        p = power.fuse_pose.apply(np.array(pt))
        j.insert(f"fuse_{k}", (p[0], p[1], p[2] + fuse.tab_mm), DOWN, fuse.tab_mm, [], "case_lower")
    return tuple(j.out)
