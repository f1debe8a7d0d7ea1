"""The design's own derived constants and the layout of every part, computed from the rig.

This is the one place that decides where things go: the case interior from the parts it holds, the
split plane, the mounts, the fans and ducts, the handles, the cut-outs, the vents and every screw
joint. Everything else (part builders, the assembly, the checks) reads a :class:`Layout`.

The design's own constants (:class:`Constants`) are the choices the rig description does not make
(how thick a lug is, how long a duct is); :func:`design_problems` checks them and the layout for what
the rig loader cannot know (a camera inside another, a handle that does not fit the case) and names
the rig key to change, so an impossible value never reaches OpenCascade.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from platform_tools.rig.frames import Pose
from platform_tools.rig import Rig

from .geom import Bounds, Vec3, pose_xyz
from .vendor.boson import BosonCore, BosonLens
from .vendor.electronics import BoxPart
from .vendor.fan import BlowerFan
from .vendor.fasteners import Insert, pick_length, thread_diameter_mm
from .vendor.jetson import JetsonOrin
from .vendor.makita_adapter import MakitaAdapter
from .vendor.makita_battery import MakitaBattery
from .vendor.panel import PanelPart
from .vendor.zed_link import ZedLinkQuad
from .vendor.zed_x import ZedX

SIDES = (("left", 1.0), ("right", -1.0))


@dataclass(frozen=True)
class Constants:
    """Choices of this design that the rig description does not make (mm unless named)."""
    heat_sink_base_mm: float = 5.0       # copper block under each sleeve; holds the tapped M3 holes
    tapped_engagement_min_mm: float = 3.0
    duct_length_mm: float = 12.0         # fan outlet to the heat sink's fin bank
    duct_wall_mm: float = 1.2
    fan_plate_mm: float = 4.0            # the plate the fan is screwed to
    orin_standoff_min_mm: float = 5.0
    orin_standoff_diameter_mm: float = 8.0
    mount_shelf_mm: float = 6.0          # ZED X shelf
    mount_leg_mm: float = 8.0            # ZED mount legs (either side of the screw head)
    lug_width_mm: float = 12.0           # case split lugs, along the wall
    lug_protrusion_mm: float = 10.0
    lid_lug_mm: float = 4.0
    handle_post_width_mm: float = 16.0
    handle_foot_mm: float = 6.0
    handle_flange_mm: float = 12.0
    fov_margin_deg: float = 2.0          # windows are cut this much wider than the field of view
    fov_length_mm: float = 400.0         # how far ahead the field-of-view frusta are checked
    battery_screw_engagement_mm: float = 5.0   # thread depth in the dock adapter (estimate)
    exploded_mm: float = 60.0

    def __post_init__(self) -> None:
        for name, value in vars(self).items():
            if not value > 0:
                raise ValueError(f"design constant {name} must be > 0, got {value}")
        if self.duct_wall_mm >= self.duct_length_mm:
            raise ValueError("duct_wall_mm must be thinner than the duct is long")


C = Constants()


@dataclass(frozen=True)
class DesignProblem:
    key: str       # the rig key (or design constant) to change
    message: str

    def __str__(self) -> str:
        return f"{self.key}: {self.message}"


class DesignError(Exception):
    def __init__(self, problems: list[DesignProblem]):
        self.problems = problems
        super().__init__("\n".join(str(p) for p in problems))


@dataclass(frozen=True)
class Hole:
    """A hole a printed (or machined) part gets: from ``origin`` along ``direction``."""
    part: str
    origin: Vec3
    direction: Vec3
    diameter: float
    depth: float


@dataclass(frozen=True)
class Joint:
    """One screw and what it holds: the screw's head sits at ``head`` and its shank runs along
    ``direction`` through ``grip_mm`` of clamped parts into ``host`` (an insert, a tapped hole in a
    bought or machined part, or a self-tapping pilot hole)."""
    name: str
    screw_id: str
    thread: str
    length_mm: float
    head: Vec3
    direction: Vec3
    grip_mm: float
    kind: str                  # "insert" | "tapped" | "self_tap"
    host: str                  # node name the thread engages
    holes: tuple[Hole, ...]

    @property
    def diameter_mm(self) -> float:
        return thread_diameter_mm(self.thread)

    @property
    def engagement_mm(self) -> float:
        return self.length_mm - self.grip_mm

    def point(self, along_mm: float) -> Vec3:
        return tuple(np.asarray(self.head) + along_mm * np.asarray(self.direction))

    def pose(self) -> Pose:
        """The screw's frame: z axis back along the shank (head up)."""
        return frame_z(tuple(-v for v in self.direction), self.head)

    def insert_pose(self) -> Pose:
        return frame_z(tuple(-v for v in self.direction), self.point(self.grip_mm))


def frame_z(z_axis: Vec3, origin: Vec3) -> Pose:
    from .geom import pose_axis_z_to
    return pose_axis_z_to(z_axis, origin)


def placed_bounds(local: Bounds, pose: Pose) -> Bounds:
    corners = np.array([[x, y, z] for x in (local.lo[0], local.hi[0]) for y in (local.lo[1], local.hi[1])
                        for z in (local.lo[2], local.hi[2])])
    p = pose.apply(corners)
    return Bounds(tuple(p.min(axis=0)), tuple(p.max(axis=0)))


@dataclass(frozen=True)
class ThermalSide:
    side: str
    sign: float
    pose: Pose                  # camera body frame in the rig (from rig.sensor_frames())
    heat_sink: Bounds           # rig frame
    fin_bank: Bounds            # the outboard fin bank, rig frame
    fan_pose: Pose
    fan: Bounds                 # rig frame
    duct_in: Bounds             # the fan outlet face (rig)
    duct_out: Bounds            # the fin bank entry face (rig)
    fan_plate: Bounds
    fan_boss: Bounds


@dataclass
class Layout:
    """Where everything is, in the rig frame (mm). Built by :func:`layout`."""
    rig: Rig
    c: Constants
    wall: float
    clear: float
    gap: float
    min_wall: float
    insert: Insert
    zed: ZedX
    zed_pose: Pose
    zed_box: Bounds
    core: BosonCore
    lens: BosonLens
    thermal: dict[str, ThermalSide]
    fan_part: BlowerFan
    thermal_bar: Bounds
    zed_mount_foot: Bounds
    zed_mount_legs: tuple[Bounds, Bounds]
    zed_mount_shelf: Bounds
    orin: JetsonOrin
    orin_pose: Pose
    orin_box: Bounds
    standoff_h: float
    card: ZedLinkQuad
    card_pose: Pose
    converter: BoxPart
    converter_pose: Pose
    fuse: BoxPart
    fuse_pose: Pose
    battery: MakitaBattery
    battery_pose: Pose
    adapter: MakitaAdapter
    adapter_pose: Pose
    battery_mount: Bounds
    interior: Bounds
    outer: Bounds
    split_z: float
    lugs: list[tuple[float, float]] = field(default_factory=list)       # (x, side sign)
    pads: list[Bounds] = field(default_factory=list)
    handle_poses: dict[str, Pose] = field(default_factory=dict)
    panel_parts: dict[str, tuple[PanelPart, Pose]] = field(default_factory=dict)
    vents: list[Bounds] = field(default_factory=list)
    port_cutout: Bounds | None = None
    joints: list[Joint] = field(default_factory=list)

    # ------------------------------------------------------------------ views
    def holes_for(self, part: str) -> tuple[Hole, ...]:
        return tuple(h for j in self.joints for h in j.holes if h.part == part)

    def handle_geometry(self) -> "HandleGeometry":
        h = self.rig.desc.enclosure.handles
        return HandleGeometry(h.grip_diameter_mm, h.grip_length_mm, h.clearance_mm - self.pad_mm,
                              self.c.handle_post_width_mm, self.c.handle_foot_mm, self.c.handle_flange_mm)

    @property
    def pad_mm(self) -> float:
        return self.insert.hole_depth_mm

    def screw_hole_mm(self, thread: str) -> float:
        holes = self.rig.desc.printing.holes
        name = thread.split()[0]
        if name in holes:
            return getattr(holes[name], f"{self.rig.desc.enclosure.screw_fit}_mm")
        return thread_diameter_mm(thread) + 2 * self.rig.desc.printing.fits.sliding_mm


@dataclass(frozen=True)
class HandleGeometry:
    grip_d: float
    grip_length: float
    post_height: float     # from the pad's top face to the grip
    post_width: float
    foot: float
    flange: float

    def foot_screw_x(self) -> list[float]:
        """x of the foot screws in the handle frame, two per foot."""
        px = self.grip_length / 2 - self.post_width / 2
        off = self.post_width / 2 + self.flange / 2
        return [s * px + d * off for s in (-1, 1) for d in (-1, 1)]

    def foot_bounds(self) -> list[Bounds]:
        px = self.grip_length / 2 - self.post_width / 2
        half = self.post_width / 2 + self.flange
        return [Bounds((s * px - half, -self.grip_d / 2, 0.0), (s * px + half, self.grip_d / 2, self.foot))
                for s in (-1, 1)]


# ============================================================================ layout
def layout(rig: Rig, c: Constants = C) -> Layout:
    """Compute the layout; raises :class:`DesignError` naming the rig keys when it cannot be made."""
    problems = design_problems(rig, c)
    if problems:
        raise DesignError(problems)
    return _layout(rig, c)


def design_problems(rig: Rig, c: Constants = C) -> list[DesignProblem]:
    """What makes the design impossible, before any geometry is built."""
    problems = list(_input_problems(rig))
    if problems:
        return problems
    try:
        lay = _layout(rig, c)
    except ValueError as exc:  # a stock screw or a box that cannot be made from these values
        return [DesignProblem("enclosure", f"the layout cannot be made from these values: {exc}")]
    return list(_layout_problems(lay))


def _input_problems(rig: Rig):
    d = rig.desc
    e = d.enclosure
    p = d.printing.printer
    min_wall = p.nozzle_mm * p.min_wall_nozzles
    if e.heat_sink.fin_count > 1:
        hs = e.heat_sink
        height = rig.part(d.sensors.thermal.part).envelope_mm.z.value + 2 * hs.wall_mm
        gap = (height - hs.fin_count * hs.fin_thickness_mm) / (hs.fin_count - 1)
        if gap < 2 * hs.fin_thickness_mm * 0.5:
            yield DesignProblem("enclosure.heat_sink.fin_count",
                                f"{hs.fin_count} fins of {hs.fin_thickness_mm:g} mm on a {height:g} mm tall heat sink "
                                f"leave {gap:.2f} mm between fins; expected at least {hs.fin_thickness_mm:g} mm")
    if e.vents.slot_width_mm < min_wall:
        yield DesignProblem("enclosure.vents.slot_width_mm", f"{e.vents.slot_width_mm:g} mm is narrower than a wall")
    if e.corner_radius_mm >= e.handles.grip_diameter_mm:
        yield DesignProblem("enclosure.corner_radius_mm", "is larger than the handle grip; expected a few mm")
    zed = d.sensors.zed_x.part
    zw = rig.part(zed).envelope_mm.y.value
    zb = rig.dim(zed, "baseline_mm")
    win = rig.dim(zed, "lens_window_diameter_mm")
    if zb + win > zw:
        yield DesignProblem(f"parts.{zed}.dims.baseline_mm",
                            f"{zb:g} mm baseline with {win:g} mm lens windows does not fit a {zw:g} mm wide camera "
                            f"(expected baseline <= {zw - win:g} mm)")


def _layout(rig: Rig, c: Constants) -> Layout:
    d = rig.desc
    e = d.enclosure
    p = d.printing.printer
    wall, clear, gap = e.wall_mm, e.component_clearance_mm, e.heat_sink_gap_mm
    min_wall = p.nozzle_mm * p.min_wall_nozzles
    insert = Insert.from_rig(rig, e.insert, "M3")
    frames = rig.sensor_frames()

    # --- cameras
    zed = ZedX.from_rig(rig, d.sensors.zed_x.part)
    zed_pose = frames["zed_x"].T_rig
    zed_box = placed_bounds(zed.bounds(), zed_pose)
    core = BosonCore.from_rig(rig, d.sensors.thermal.part, d.sensors.thermal.lens)
    lens = BosonLens.from_rig(rig, d.sensors.thermal.lens)
    fan_part = BlowerFan.from_rig(rig, _part_of_kind(rig, "fan"))
    hs = e.heat_sink
    cb = core.bounds()
    sleeve = Bounds((cb.lo[0], cb.lo[1] - hs.wall_mm, cb.lo[2] - hs.wall_mm),
                    (cb.hi[0], cb.hi[1] + hs.wall_mm, cb.hi[2] + hs.wall_mm))
    hs_local = Bounds((sleeve.lo[0], sleeve.lo[1] - hs.fin_height_mm, sleeve.lo[2] - c.heat_sink_base_mm),
                      (sleeve.hi[0], sleeve.hi[1] + hs.fin_height_mm, sleeve.hi[2]))
    fx, fy, fz = fan_part.size
    thermal: dict[str, ThermalSide] = {}
    for side, s in SIDES:
        pose = frames[f"thermal_{side}"].T_rig
        hsb = placed_bounds(hs_local, pose)
        fin_local = (Bounds((sleeve.lo[0], sleeve.hi[1], sleeve.lo[2]), (sleeve.hi[0], hs_local.hi[1], sleeve.hi[2]))
                     if s > 0 else
                     Bounds((sleeve.lo[0], hs_local.lo[1], sleeve.lo[2]), (sleeve.hi[0], sleeve.lo[1], sleeve.hi[2])))
        fin = placed_bounds(fin_local, pose)
        # fan: standing, inlet (local +z) facing out of the case, outlet (local +x) towards the fins
        rot = Pose.from_xyz_rpy_deg((0, 0, 0), (-90.0 * s, 0, 0))
        out_local = fan_part.outlet()
        out_centre = rot.apply(np.array(out_local.centre))
        fan_front = hsb.lo[0] - gap - c.duct_length_mm
        target = np.array([fan_front - fx / 2, fin.centre[1], fin.centre[2]])
        centre = target - np.array([0.0, out_centre[1], out_centre[2]])
        fan_pose = Pose(rot.R, centre)
        fan_box = placed_bounds(fan_part.bounds(), fan_pose)
        out_box = placed_bounds(out_local, fan_pose)
        duct_in = Bounds((fan_box.hi[0], out_box.lo[1], out_box.lo[2]), (fan_box.hi[0] + 0.01, out_box.hi[1], out_box.hi[2]))
        duct_out = Bounds((hsb.lo[0] - gap - 0.01, fin.lo[1], fin.lo[2]), (hsb.lo[0] - gap, fin.hi[1], fin.hi[2]))
        inboard = fan_box.lo[1] if s > 0 else fan_box.hi[1]
        plate_y = (inboard - c.fan_plate_mm, inboard) if s > 0 else (inboard, inboard + c.fan_plate_mm)
        thermal[side] = ThermalSide(side, s, pose, hsb, fin, fan_pose, fan_box, duct_in, duct_out,
                                    Bounds((fan_box.lo[0] - 12.0, plate_y[0], fan_box.lo[2] - 1), (duct_out.lo[0], plate_y[1], fan_box.hi[2])),
                                    fan_box)  # plate and boss reach the floor once it is known (below)
    # --- thermal bar under both heat sinks, sitting on the floor
    hs_all = [t.heat_sink for t in thermal.values()]
    bar_t = insert.hole_depth_mm + min_wall
    bar = Bounds((min(b.lo[0] for b in hs_all), min(b.lo[1] for b in hs_all), min(b.lo[2] for b in hs_all) - bar_t),
                 (max(b.hi[0] for b in hs_all), max(b.hi[1] for b in hs_all), min(b.lo[2] for b in hs_all)))
    fan_bottom = min(t.fan.lo[2] for t in thermal.values())
    floor_in = min(bar.lo[2], fan_bottom - clear)
    if floor_in < bar.lo[2]:  # the bar stands on the floor
        bar = Bounds((bar.lo[0], bar.lo[1], floor_in), bar.hi)
    # fan plates go down to the floor, with a boss behind the fan for the floor screw
    boss_w = insert.outer_diameter_mm + 2 * (min_wall + 1.0)
    for side, t in list(thermal.items()):
        top = max(t.fan.hi[2], t.duct_in.hi[2] + c.duct_wall_mm, t.duct_out.hi[2] + c.duct_wall_mm)
        plate = Bounds((t.fan_plate.lo[0], t.fan_plate.lo[1], floor_in), (t.fan_plate.hi[0], t.fan_plate.hi[1], top))
        y0 = plate.lo[1] if t.sign > 0 else plate.hi[1] - boss_w
        boss = Bounds((plate.lo[0], y0, floor_in), (t.fan.lo[0] - clear, y0 + boss_w, floor_in + bar_t))
        thermal[side] = ThermalSide(**{**vars(t), "fan_plate": plate, "fan_boss": boss})

    # --- ZED X mount: shelf under the camera, two legs either side of the 1/4-20 head, a foot on the floor
    zscrew = rig.part("quarter20_screw").dims
    head_d = zscrew["head_diameter_mm"].value
    shelf = Bounds((zed_box.lo[0] + clear, -(head_d / 2 + clear + c.mount_leg_mm + 6), zed_box.lo[2] - c.mount_shelf_mm),
                   (zed_box.hi[0] - wall - clear, head_d / 2 + clear + c.mount_leg_mm + 6, zed_box.lo[2]))
    leg_x = (bar.lo[0] - clear - 14.0, bar.lo[0] - clear)
    legs = tuple(Bounds((leg_x[0], s * (head_d / 2 + clear) if s > 0 else -(head_d / 2 + clear + c.mount_leg_mm), floor_in),
                        (leg_x[1], (head_d / 2 + clear + c.mount_leg_mm) if s > 0 else -(head_d / 2 + clear), shelf.lo[2]))
                 for s in (1, -1))
    foot = Bounds((leg_x[0], -(head_d / 2 + clear + c.mount_leg_mm + 10), floor_in),
                  (leg_x[1], head_d / 2 + clear + c.mount_leg_mm + 10, floor_in + bar_t))
    shelf = Bounds((min(shelf.lo[0], leg_x[0]), shelf.lo[1], shelf.lo[2]), shelf.hi)

    # --- computer behind the cameras
    orin = JetsonOrin.from_rig(rig, _part_of_kind(rig, "computer"))
    cam_back = min([zed_box.lo[0] - clear, leg_x[0] - clear] + [t.fan_plate.lo[0] - gap for t in thermal.values()])
    standoff_h = max(c.orin_standoff_min_mm, rig.dim(e.screw, "head_height_mm") + 2 * clear)
    ox, oy, oz = orin.size
    orin_pose = pose_xyz(cam_back - ox / 2, 0.0, floor_in + standoff_h)
    orin_box = placed_bounds(orin.bounds(), orin_pose)
    card = ZedLinkQuad.from_rig(rig, d.sync.source_part)
    card_pose = pose_xyz(orin_pose.t[0], 0.0, orin_box.hi[2] + clear)
    card_box = placed_bounds(card.bounds(), card_pose)

    # --- the case interior from what it holds
    half_in = max([abs(zed_box.lo[1]) + clear, abs(zed_box.hi[1]) + clear, oy / 2 + clear]
                  + [max(abs(t.fan.lo[1]), abs(t.fan.hi[1])) + gap for t in thermal.values()]
                  + [max(abs(t.heat_sink.lo[1]), abs(t.heat_sink.hi[1])) + gap for t in thermal.values()])
    split_z = zed_box.lo[2] - clear
    top_in = max(zed_box.hi[2], card_box.hi[2]) + clear
    if e.handles.sides:  # the lid's side walls carry the side handles' feet and pads
        top_in = max(top_in, split_z + e.handles.grip_diameter_mm + 4 + 2 * wall + 2)
    front_out = zed_box.hi[0]
    rear_in = orin_box.lo[0] - clear
    interior = Bounds((rear_in, -half_in, floor_in), (front_out - wall, half_in, top_in))
    outer = interior.grown(wall)
    outer = Bounds((outer.lo[0], outer.lo[1], outer.lo[2]), (front_out, outer.hi[1], outer.hi[2]))

    # --- power: converter on the right wall, fuse on the floor, battery under the case
    conv = BoxPart.from_rig(rig, _part_of_kind(rig, "converter"))
    cx, cy, cz = conv.size
    conv_pose = Pose.from_xyz_rpy_deg((orin_box.hi[0] - cx / 2, -half_in, floor_in + clear + cy / 2), (-90.0, 0, 0))
    fuse = BoxPart.from_rig(rig, _part_of_kind(rig, "fuse"))
    fuse_pose = pose_xyz(orin_box.lo[0] + fuse.size[0] / 2 + clear,
                         orin_box.hi[1] + clear + fuse.size[1] / 2, floor_in)
    adapter = MakitaAdapter.from_rig(rig, _part_of_kind(rig, "battery_adapter"))
    battery = MakitaBattery.from_rig(rig, _part_of_kind(rig, "battery"))
    plate_t = bar_t
    ax, ay, az = adapter.size
    bm = Bounds((orin_pose.t[0] - ax / 2, -ay / 2, outer.lo[2] - plate_t), (orin_pose.t[0] + ax / 2, ay / 2, outer.lo[2]))
    adapter_pose = pose_xyz(orin_pose.t[0], 0.0, bm.lo[2] - az)
    bx = battery.size[0]
    battery_pose = pose_xyz(orin_pose.t[0] + ax / 2 - bx / 2, 0.0, adapter_pose.t[2])

    lay = Layout(rig, c, wall, clear, gap, min_wall, insert, zed, zed_pose, zed_box, core, lens, thermal, fan_part,
                 bar, foot, legs, shelf, orin, orin_pose, orin_box, standoff_h, card, card_pose, conv, conv_pose,
                 fuse, fuse_pose, battery, battery_pose, adapter, adapter_pose, bm, interior, outer, split_z)
    _place_handles(lay)
    _place_lugs(lay)
    _place_panel_parts(lay)
    _place_cutouts(lay)
    _place_vents(lay)
    _place_joints(lay)
    return lay


def _part_of_kind(rig: Rig, kind: str) -> str:
    for pid, part in rig.desc.parts.items():
        if part.kind.value == kind:
            return pid
    raise KeyError(f"the rig has no part of kind {kind}")


# ---------------------------------------------------------------------------- handles, lugs
def _place_handles(lay: Layout) -> None:
    h = lay.rig.desc.enclosure.handles
    o = lay.outer
    x_mid = (o.lo[0] + o.hi[0]) / 2
    lid_mid = (lay.split_z + o.hi[2]) / 2
    if h.top:
        lay.handle_poses["top"] = pose_xyz(x_mid, 0.0, o.hi[2] + lay.pad_mm)
    if h.sides:
        lay.handle_poses["left"] = Pose.from_xyz_rpy_deg((x_mid, o.hi[1] + lay.pad_mm, lid_mid), (-90.0, 0, 0))
        lay.handle_poses["right"] = Pose.from_xyz_rpy_deg((x_mid, o.lo[1] - lay.pad_mm, lid_mid), (90.0, 0, 0))
    g = lay.handle_geometry()
    for pose in lay.handle_poses.values():
        for fb in g.foot_bounds():
            pad_local = Bounds((fb.lo[0] - 2, fb.lo[1] - 2, -lay.pad_mm - 0.5 * lay.wall), (fb.hi[0] + 2, fb.hi[1] + 2, 0.0))
            lay.pads.append(placed_bounds(pad_local, pose))


def _place_lugs(lay: Layout) -> None:
    o = lay.outer
    w = lay.c.lug_width_mm
    xs = [o.hi[0] - w / 2 - lay.rig.desc.enclosure.corner_radius_mm - 2,
          (o.lo[0] + o.hi[0]) / 2,
          o.lo[0] + w / 2 + lay.rig.desc.enclosure.corner_radius_mm + 2]
    lay.lugs = [(x, s) for x in xs for s in (1.0, -1.0)]


def lug_bounds(lay: Layout, x: float, s: float) -> Bounds:
    """The lug pair's footprint, both halves and their gussets (for clash tests with pads)."""
    o = lay.outer
    p = lay.c.lug_protrusion_mm
    y0, y1 = (o.hi[1] - 0.5, o.hi[1] + p) if s > 0 else (o.lo[1] - p, o.lo[1] + 0.5)
    lower_t = lay.insert.hole_depth_mm + lay.min_wall
    return Bounds((x - lay.c.lug_width_mm / 2, y0, lay.split_z - lower_t - p),
                  (x + lay.c.lug_width_mm / 2, y1, lay.split_z + lay.c.lid_lug_mm + p))


def lug_screw_point(lay: Layout, x: float, s: float) -> Vec3:
    o = lay.outer
    y = o.hi[1] + lay.c.lug_protrusion_mm / 2 + 0.25 if s > 0 else o.lo[1] - lay.c.lug_protrusion_mm / 2 - 0.25
    return (x, y, lay.split_z)


# ---------------------------------------------------------------------------- panel parts
def _place_panel_parts(lay: Layout) -> None:
    rig, o, w = lay.rig, lay.outer, lay.wall
    lid_mid = (lay.split_z + lay.interior.hi[2]) / 2
    side_y = lay.orin_box.hi[1] + lay.clear + 14.0
    sw = PanelPart.switch(rig, _part_of_kind(rig, "switch"), w)
    bt = PanelPart.button(rig, _part_of_kind(rig, "button"), w)
    lay.panel_parts["power_switch"] = (sw, Pose.from_xyz_rpy_deg((o.lo[0], -side_y, lid_mid), (0, 0, 180.0)))
    lay.panel_parts["record_button"] = (bt, Pose.from_xyz_rpy_deg((o.lo[0], side_y, lid_mid), (0, 0, 180.0)))
    ant = PanelPart.antenna(rig, _part_of_kind(rig, "antenna"), w)
    ax = o.lo[0] + max(sw.size[0], bt.size[0]) + w + lay.clear + ant.size[1] / 2 + 4.0
    for side, s in SIDES:
        lay.panel_parts[f"wifi_antenna_{side}"] = (ant, Pose.from_xyz_rpy_deg((ax, s * side_y, o.hi[2]), (0, -90.0, 0)))


# ---------------------------------------------------------------------------- cut-outs and vents
def fov_half_angles_deg(lay: Layout) -> dict[str, tuple[float, float]]:
    """Half angles (horizontal, vertical) of each camera's field of view, for frusta and windows.
    The fisheye Boson gets its diagonal half angle on both axes (a cone that holds the whole image)."""
    out = {}
    zm = lay.rig.camera_model(lay.rig.desc.sensors.zed_x.camera_model)
    vz = zm.vfov_deg.value if zm.vfov_deg else zm.hfov_deg.value * zm.height_px / zm.width_px
    out["zed_x"] = (zm.hfov_deg.value / 2, vz / 2)
    tm = lay.rig.camera_model(lay.rig.desc.sensors.thermal.camera_model)
    h = tm.hfov_deg.value / 2
    diag = h * math.hypot(tm.width_px, tm.height_px) / tm.width_px   # equidistant: angle ~ radius
    out["thermal"] = (diag, diag)
    return out


def _place_cutouts(lay: Layout) -> None:
    o, b = lay.outer, lay.orin_box
    top = b.lo[2] + lay.orin.port_panel_height_mm + lay.clear
    if lay.split_z - top < 2 * lay.wall or top > lay.split_z:  # a long window becomes a notch from the split
        top = max(top, lay.split_z + 0.01)
    lay.port_cutout = Bounds((o.lo[0] - 1, b.lo[1] - lay.clear, b.lo[2] - lay.clear), (lay.interior.lo[0] + 1, b.hi[1] + lay.clear, top))


def _place_vents(lay: Layout) -> None:
    """Vertical slots in the lower side walls beside the fans and the computer, clear of lugs and the
    converter, and exhaust slots in the front wall ahead of each fin bank."""
    v = lay.rig.desc.enclosure.vents
    o, i = lay.outer, lay.interior
    z_mid = (i.lo[2] + lay.split_z) / 2
    zlen = min(v.slot_length_mm, lay.split_z - i.lo[2] - 2 * lay.wall)
    pitch = v.slot_width_mm + max(lay.min_wall * 2, v.slot_width_mm)
    keep_out: dict[float, list[tuple[float, float]]] = {1.0: [], -1.0: []}
    for x, s in lay.lugs:
        keep_out[s].append((x - lay.c.lug_width_mm / 2 - lay.wall, x + lay.c.lug_width_mm / 2 + lay.wall))
    cb = placed_bounds(lay.converter.bounds(), lay.converter_pose)
    keep_out[-1.0].append((cb.lo[0] - lay.wall, cb.hi[0] + lay.wall))
    zones = [(t.fan.lo[0], t.fan.hi[0]) for t in lay.thermal.values()] + [(lay.orin_box.lo[0], lay.orin_box.hi[0])]
    for s in (1.0, -1.0):
        x = i.lo[0] + lay.wall + v.slot_width_mm
        while x < i.hi[0] - lay.wall - v.slot_width_mm:
            x0, x1 = x - v.slot_width_mm / 2, x + v.slot_width_mm / 2
            if any(a <= x0 and x1 <= bb for a, bb in zones) and not any(x1 > a and x0 < bb for a, bb in keep_out[s]):
                y0, y1 = (i.hi[1] - 0.5, o.hi[1] + 0.5) if s > 0 else (o.lo[1] - 0.5, i.lo[1] + 0.5)
                lay.vents.append(Bounds((x0, y0, z_mid - zlen / 2), (x1, y1, z_mid + zlen / 2)))
            x += pitch
    # front exhaust ahead of each outboard fin bank, outside the window cone
    half = fov_half_angles_deg(lay)["thermal"][0] + lay.c.fov_margin_deg
    for t in lay.thermal.values():
        cam = t.pose.t
        r_win = (o.hi[0] - cam[0]) * math.tan(math.radians(half))
        lens_r = lay.lens.diameter_mm / 2 + lay.clear
        r_win = max(r_win, lens_r)
        y = t.fin_bank.centre[1]
        while abs(y) + v.slot_width_mm / 2 + lay.min_wall < i.hi[1]:
            if abs(y - cam[1]) - v.slot_width_mm / 2 >= r_win + lay.min_wall:
                zl = min(v.slot_length_mm, t.fin_bank.size[2])
                lay.vents.append(Bounds((i.hi[0] - 0.5, y - v.slot_width_mm / 2, t.fin_bank.centre[2] - zl / 2),
                                        (o.hi[0] + 0.5, y + v.slot_width_mm / 2, t.fin_bank.centre[2] + zl / 2)))
            y += t.sign * pitch


# ---------------------------------------------------------------------------- joints
def _place_joints(lay: Layout) -> None:
    rig = lay.rig
    e = rig.desc.enclosure
    m3 = "M3"
    ins = lay.insert
    eng_ins = (ins.length_mm * 0.5, ins.hole_depth_mm - 0.1)   # a 2 mm stock step always fits this window
    clr = lay.screw_hole_mm(m3)
    joints = lay.joints
    down, up = (0.0, 0.0, -1.0), (0.0, 0.0, 1.0)

    def insert_joint(name, head, direction, grip, clamped: list[str], host: str):
        L = pick_length(grip, *eng_ins)
        hd = np.asarray(head)
        dvec = np.asarray(direction)
        holes = tuple(Hole(p, tuple(hd - 0.01 * dvec), direction, clr, grip + 0.02) for p in clamped)
        holes += (Hole(host, tuple(hd + grip * dvec - 0.01 * dvec), direction, ins.hole_diameter_mm, ins.hole_depth_mm + 0.01),)
        joints.append(Joint(name, e.screw, m3, L, head, direction, grip, "insert", host, holes))

    def tapped_joint(name, screw_id, thread, head, direction, grip, clamped, host, depth, cut_host=None):
        L = pick_length(grip, min(lay.c.tapped_engagement_min_mm, depth * 0.6), depth)
        hd, dvec = np.asarray(head), np.asarray(direction)
        hole_d = lay.screw_hole_mm(thread)
        holes = tuple(Hole(p, tuple(hd - 0.01 * dvec), direction, hole_d, grip + 0.02) for p in clamped)
        if cut_host:  # a tapped hole we machine ourselves: tap drill
            holes += (Hole(cut_host, tuple(hd + grip * dvec - 0.01 * dvec), direction,
                           0.85 * thread_diameter_mm(thread), depth + 0.5),)
        joints.append(Joint(name, screw_id, thread, L, head, direction, grip, "tapped", host, holes))

    fo = lay.outer.lo[2]
    # case split: lid lug screwed down into an insert in the lower lug
    for k, (x, s) in enumerate(lay.lugs):
        px, py, pz = lug_screw_point(lay, x, s)
        head = (px, py, pz + lay.c.lid_lug_mm)
        insert_joint(f"lug_{k}", head, down, lay.c.lid_lug_mm, ["case_lid"], "case_lower")
        # the head's counterbore through the lug's gusset
        hd = rig.dim(e.screw, "head_diameter_mm") + 2 * rig.desc.printing.fits.loose_mm
        j = joints[-1]
        joints[-1] = Joint(j.name, j.screw_id, j.thread, j.length_mm, j.head, j.direction, j.grip_mm, j.kind, j.host,
                           j.holes + (Hole("case_lid", head, up, hd, lay.c.lug_protrusion_mm + 1.0),))
    # handles: two screws per foot into inserts in the pads
    g = lay.handle_geometry()
    for hname, pose in lay.handle_poses.items():
        for k, hx in enumerate(g.foot_screw_x()):
            head = tuple(pose.apply(np.array([hx, 0.0, g.foot])))
            d = tuple(pose.rotate(np.array([0.0, 0.0, -1.0])))
            insert_joint(f"handle_{hname}_{k}", head, d, g.foot, [f"handle_{hname}"], "case_lid")
    # thermal bar: two screws from under the floor into inserts in the bar
    bar = lay.thermal_bar
    inner = sorted(abs(t.heat_sink.lo[1]) if t.sign > 0 else abs(t.heat_sink.hi[1]) for t in lay.thermal.values())[0]
    for k, y in enumerate((bar.centre[1] + inner / 2, bar.centre[1] - inner / 2)):
        insert_joint(f"thermal_mount_{k}", (bar.centre[0], y, fo), up, lay.wall, ["case_lower"], "thermal_mount")
    # heat sinks: two screws from under the floor, through the bar, tapped in the copper base
    for side, t in lay.thermal.items():
        cb = placed_bounds(lay.core.bounds(), t.pose)
        for k, dy in enumerate((-6.0, 6.0)):
            tapped_joint(f"heat_sink_{side}_{k}", e.screw, m3, (cb.centre[0], cb.centre[1] + dy, fo), up,
                         lay.wall + (bar.hi[2] - bar.lo[2]), ["case_lower", "thermal_mount"], f"heat_sink_{side}",
                         lay.c.heat_sink_base_mm - 1.0, cut_host=f"heat_sink_{side}")
    # ZED mount: two floor screws into its foot; the camera on its 1/4-20 thread
    foot = lay.zed_mount_foot
    for k, y in enumerate((foot.hi[1] - 5.0, foot.lo[1] + 5.0)):
        insert_joint(f"zed_mount_{k}", (foot.centre[0], y, fo), up, lay.wall, ["case_lower"], "zed_mount")
    zm = [m for m in rig.part(rig.desc.sensors.zed_x.part).mounting if m.face.value == "bottom"][0]
    for k, pt in enumerate(lay.zed.mount_points()):
        p = lay.zed_pose.apply(np.array(pt))
        shelf_t = lay.zed_mount_shelf.hi[2] - lay.zed_mount_shelf.lo[2]
        tapped_joint(f"zed_x_{k}", "quarter20_screw", zm.thread, (p[0], p[1], p[2] - shelf_t), up, shelf_t,
                     ["zed_mount"], "zed_x", zm.depth_mm)
    # fans: self-tapping screws through the fan into its plate; the fan mount's boss screwed to the floor
    fan_screw = rig.part("m2p5_screw")
    pilot = fan_screw.dims["pilot_hole_diameter_mm"].value
    for side, t in lay.thermal.items():
        zf = lay.fan_part.size[2]
        for k, (u, v) in enumerate(lay.fan_part.holes()):
            head = tuple(t.fan_pose.apply(np.array([u, v, zf / 2])))
            d = tuple(t.fan_pose.rotate(np.array([0.0, 0.0, -1.0])))
            L = pick_length(zf, 2.5, lay.c.fan_plate_mm - 0.4)
            hd, dv = np.asarray(head), np.asarray(d)
            holes = (Hole(f"fan_mount_{side}", tuple(hd + zf * dv - 0.01 * dv), d, pilot, lay.c.fan_plate_mm + 0.02),)
            joints.append(Joint(f"fan_{side}_{k}", "m2p5_screw", "M2.5", L, head, d, zf, "self_tap",
                                f"fan_mount_{side}", holes))
        boss = t.fan_boss
        insert_joint(f"fan_mount_{side}", (boss.centre[0], boss.centre[1], fo), up, lay.wall, ["case_lower"],
                     f"fan_mount_{side}")
    # Orin: from under the floor, through a standoff, into the devkit's threads
    for k, pt in enumerate(lay.orin.mount_points()):
        p = lay.orin_pose.apply(np.array(pt))
        tapped_joint(f"orin_{k}", e.screw, m3, (p[0], p[1], fo), up, lay.wall + lay.standoff_h,
                     ["case_lower", f"orin_standoff_{k}"], lay.orin.part_id, lay.orin.mount_depth_mm)
    # battery dock: from inside the case, through the floor and the battery mount, into the adapter
    bm = lay.battery_mount
    ax, ay, _ = lay.adapter.size
    for k, (u, v) in enumerate([(-ax / 2 + 10, ay / 2 - 8), (ax / 2 - 10, ay / 2 - 8), (-ax / 2 + 10, -ay / 2 + 8), (ax / 2 - 10, -ay / 2 + 8)]):
        tapped_joint(f"battery_{k}", e.screw, m3, (bm.centre[0] + u, v, lay.interior.lo[2]), down,
                     lay.wall + (bm.hi[2] - bm.lo[2]), ["case_lower", "battery_mount"], lay.adapter.part_id,
                     lay.c.battery_screw_engagement_mm)
    # converter: through the right wall into its base threads
    for k, pt in enumerate(lay.converter.mount_points()):
        p = lay.converter_pose.apply(np.array(pt))
        d = tuple(lay.converter_pose.rotate(np.array([0.0, 0.0, 1.0])))
        head = tuple(np.asarray(p) - lay.wall * np.asarray(d))
        tapped_joint(f"converter_{k}", e.screw, m3, head, d, lay.wall, ["case_lower"], lay.converter.part_id,
                     lay.converter.mount_depth_mm)


# ============================================================================ invariants
def _layout_problems(lay: Layout):
    rig = lay.rig
    t = rig.desc.sensors.thermal
    # the thermal pair must sit below the ZED X with room for its heat sinks and the ZED shelf
    hs_top = max(s.heat_sink.hi[2] for s in lay.thermal.values())
    if hs_top > lay.zed_mount_shelf.lo[2] - rig.desc.enclosure.heat_sink_gap_mm:
        yield DesignProblem("sensors.thermal.pose.xyz_mm",
                            f"the Boson heat sinks reach z = {hs_top:.1f} mm, into the ZED X and its mount (shelf "
                            f"underside at {lay.zed_mount_shelf.lo[2]:.1f} mm); move the pair down by at least "
                            f"{hs_top - lay.zed_mount_shelf.lo[2] + rig.desc.enclosure.heat_sink_gap_mm:.1f} mm")
    inner_edge = min(abs(s.heat_sink.lo[1]) if s.sign > 0 else abs(s.heat_sink.hi[1]) for s in lay.thermal.values())
    leg_edge = max(abs(b.lo[1]) for b in lay.zed_mount_legs) if lay.zed_mount_legs else 0
    if any(lay.zed_mount_legs[0].overlaps(s.heat_sink) or lay.zed_mount_legs[1].overlaps(s.heat_sink)
           for s in lay.thermal.values()):
        yield DesignProblem("sensors.thermal.baseline_mm",
                            f"{t.baseline_mm:g} mm leaves the inner heat sink faces at |y| = {inner_edge:.1f} mm, "
                            f"inside the ZED X mount legs (|y| <= {leg_edge:.1f} mm)")
    for s in lay.thermal.values():
        lens_front = s.pose.t[0] + lay.lens.front_mm
        if lens_front > lay.outer.hi[0] - lay.wall + 1e-6:
            yield DesignProblem("sensors.thermal.pose.xyz_mm",
                                f"the {s.side} Boson lens front (x = {lens_front:.1f} mm) is ahead of the front wall's "
                                f"inner face (x = {lay.outer.hi[0] - lay.wall:.1f} mm, set by the ZED X front); "
                                f"move the pair back")
        if s.heat_sink.hi[0] + lay.gap > lay.outer.hi[0] - lay.wall:
            yield DesignProblem("sensors.thermal.pose.xyz_mm", f"the {s.side} heat sink is within the gap of the front wall")
    need = lay.insert.outer_diameter_mm + 2 * (lay.min_wall + lay.gap)   # the bar's floor screws sit between
    if 2 * inner_edge < need:
        yield DesignProblem("sensors.thermal.baseline_mm",
                            f"{t.baseline_mm:g} mm leaves {2 * inner_edge:.1f} mm between the two heat sinks; the thermal "
                            f"bar's floor screw inserts need {need:.1f} mm there (expected baseline >= "
                            f"{t.baseline_mm + need - 2 * inner_edge:.1f} mm)")
    if lay.zed_mount_foot.overlaps(lay.thermal_bar):
        yield DesignProblem("sensors.thermal.pose.xyz_mm", "the ZED X mount's foot runs into the thermal bar")
    # handles fit the case
    h = rig.desc.enclosure.handles
    g = lay.handle_geometry()
    length = lay.outer.size[0]
    foot_len = g.grip_length + 2 * g.flange + 4
    if h.top or h.sides:
        if foot_len > length - 2 * rig.desc.enclosure.corner_radius_mm:
            yield DesignProblem("enclosure.handles.grip_length_mm",
                                f"{h.grip_length_mm:g} mm grips with their feet ({foot_len:g} mm) do not fit the "
                                f"{length:.1f} mm long case; expected <= "
                                f"{length - 2 * rig.desc.enclosure.corner_radius_mm - 2 * g.flange - 4:.1f} mm")
        if g.post_height < g.foot + 2:
            yield DesignProblem("enclosure.handles.clearance_mm",
                                f"{h.clearance_mm:g} mm leaves no post between the foot and the grip; expected >= "
                                f"{g.foot + 2 + lay.pad_mm:g} mm")
    if h.sides and h.grip_diameter_mm + 4 > lay.outer.hi[2] - lay.split_z - 2 * lay.wall:
        yield DesignProblem("enclosure.handles.grip_diameter_mm",
                            f"side handle feet ({h.grip_diameter_mm + 4:g} mm tall) do not fit the lid's "
                            f"{lay.outer.hi[2] - lay.split_z:.1f} mm side walls")
    for pad in lay.pads:
        for x, s in lay.lugs:
            if pad.overlaps(lug_bounds(lay, x, s)):
                yield DesignProblem("enclosure.handles.grip_length_mm",
                                    f"a handle foot pad at x = {pad.centre[0]:.1f} mm runs into a case lug at "
                                    f"x = {x:.1f} mm; shorten the grip")
                break
    # every printed part fits the bed (the case halves are the largest)
    bed = rig.desc.printing.printer.bed_mm
    o = lay.outer
    footprint = sorted([o.size[0] + 2 * lay.c.lug_protrusion_mm * 0, o.size[1] + 2 * lay.c.lug_protrusion_mm])
    if footprint[1] > max(bed[:2]) or footprint[0] > min(bed[:2]):
        yield DesignProblem("printing.printer.bed_mm",
                            f"the case halves ({o.size[0]:.0f} x {o.size[1] + 2 * lay.c.lug_protrusion_mm:.0f} mm with "
                            f"lugs) do not fit the {bed[0]:g} x {bed[1]:g} mm bed")
    # the vents must reach the configured area (checked on the geometry too)
    v = rig.desc.enclosure.vents
    need = v.min_area_ratio * 2 * lay.fan_part.inlet_area_mm2
    have = sum(b.size[2] * (b.size[0] if b.size[1] > b.size[0] else b.size[1]) for b in lay.vents)
    if have < need:
        yield DesignProblem("enclosure.vents.slot_length_mm",
                            f"the walls take {len(lay.vents)} slots, {have:.0f} mm^2 open; the fans need "
                            f"{need:.0f} mm^2 (min_area_ratio {v.min_area_ratio:g}); use longer or wider slots")
