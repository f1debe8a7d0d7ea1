"""Power and sync: the DC-DC converter on the right wall, the fuse holder beside the Orin on two bosses
of the floor (its screw tabs on them), the cable gland that brings the battery leads up through the
floor just ahead of the fuse, the under-voltage cut-off board ahead of the gland on two more bosses, the Makita battery under
the case in its dock adapter (screwed through a printed mount plate to the floor), and the sync
breakout board on each Boson's rear connector. Rig frame, mm."""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from platform_tools.rig import Rig
from platform_tools.rig.frames import Pose

from cad.bought.base import part_of_kind
from cad.bought.electronics import BoardPart, BoxPart, FuseHolder, SyncBreakout
from cad.bought.fasteners import thread_diameter_mm
from cad.bought.gland import CableGland
from cad.bought.makita_adapter import MakitaAdapter
from cad.bought.makita_battery import MakitaBattery
from cad.geom import Bounds, placed_bounds, pose_xyz

from .cameras import Cameras
from .case import Shell
from .compute import Compute
from .errors import DesignError, DesignProblem
from .fits import Fits

#: wall beside the floor bosses' inserts (the cut-off's and the fuse holder's), beyond the printer's
#: minimum wall, on each side
CUTOFF_BOSS_WALL_EXTRA_MM = 1.0
#: a deep socket's wall around the gland's locknut (a 15 mm socket is about 21 mm across: estimate); the
#: floor bosses beside the gland stand clear of that socket's path (cad/passthrough.py checks it on the solid)
SOCKET_WALL_MM = 2.5

#: a floor boss: (x, y, diameter, height), standing on the floor's inner face (rig frame, mm)
Boss = tuple[float, float, float, float]


@dataclass(frozen=True)
class Power:
    converter: BoxPart
    converter_pose: Pose
    fuse: FuseHolder
    fuse_pose: Pose             # origin at the tabs' underside, on its bosses' tops
    adapter: MakitaAdapter
    adapter_pose: Pose
    battery: MakitaBattery
    battery_pose: Pose
    battery_mount: Bounds       # the plate between the case floor and the dock adapter
    gland: CableGland
    gland_pose: Pose            # z into the case, origin on the floor's outer face
    cutoff: BoardPart
    cutoff_pose: Pose
    cutoff_seats: tuple[Boss, ...]    # the cut-off's bosses, one under each of its holes
    fuse_bosses: tuple[Boss, ...]     # the fuse holder's, one under each tab hole
    breakout: SyncBreakout
    breakout_poses: dict[str, Pose]   # by side: on the Boson's rear face

    @property
    def gland_hole(self) -> tuple[tuple[float, float, float], float]:
        """Where the gland's hole crosses the floor's outer face, and its diameter (the gland's table)."""
        return tuple(self.gland_pose.t), self.gland.hole_d_mm

    @property
    def floor_bosses(self) -> tuple[Boss, ...]:
        """Every boss on the floor: the cut-off's, then the fuse holder's."""
        return self.cutoff_seats + self.fuse_bosses

    @property
    def converter_box(self) -> Bounds:
        return placed_bounds(self.converter.bounds(), self.converter_pose)


def place_power(rig: Rig, fits: Fits, shell: Shell, compute: Compute, cameras: Cameras) -> Power:
    """The converter on its base against the right wall beside the Orin, resting on the floor; the fuse on the
    floor beside the Orin's other side, the gland and the cut-off in the floor strip ahead of the fuse, the
    battery dock centred under the Orin with the battery's rear end flush with the dock's, a breakout behind
    each Boson."""
    clear, floor_z = fits.clear, shell.interior.lo[2]
    orin_box, orin_x = compute.orin_box, compute.orin_pose.t[0]
    conv = BoxPart.from_rig(rig, part_of_kind(rig, "converter"))
    cx, cy, _ = conv.size
    # on its base plate against the right wall (its mounting flanges on the wall), standing on its long edge on
    # the floor, its front end flush with the devkit's front: it fills the strip beside the devkit, whose right
    # face blows its exhaust over and past it to the lid's side slots (cad/layout/case.py sizes the strip)
    conv_pose = Pose.from_xyz_rpy_deg((orin_box.hi[0] - cx / 2, shell.interior.lo[1], floor_z + cy / 2),
                                      (-90.0, 0, 0))
    # the fuse holder's tabs on two bosses of the floor, an insert in each (as the cut-off's): its screws
    # go down through the tabs from inside the tray
    boss_h = fits.insert_plate_mm
    boss_d = fits.insert.outer_diameter_mm + 2 * (fits.min_wall + CUTOFF_BOSS_WALL_EXTRA_MM)
    fuse = _fuse_holder(rig, fits)
    fuse_pose = pose_xyz(orin_box.lo[0] + fuse.size[0] / 2 + clear, orin_box.hi[1] + clear + fuse.size[1] / 2,
                         floor_z + boss_h)
    adapter = MakitaAdapter.from_rig(rig, part_of_kind(rig, "battery_adapter"))
    battery = MakitaBattery.from_rig(rig, part_of_kind(rig, "battery"))
    ax, ay, az = adapter.size
    floor_out = shell.outer.lo[2]
    mount = Bounds((orin_x - ax / 2, -ay / 2, floor_out - fits.insert_plate_mm), (orin_x + ax / 2, ay / 2, floor_out))
    adapter_pose = pose_xyz(orin_x, 0.0, mount.lo[2] - az)
    battery_pose = pose_xyz(orin_x + ax / 2 - battery.size[0] / 2, 0.0, adapter_pose.t[2])
    # the floor strip between the Orin and the left wall, ahead of the fuse: the gland's locknut, then the cut-off
    strip_y = (orin_box.hi[1] + clear + shell.interior.hi[1] - clear) / 2
    gland = replace(CableGland.from_rig(rig, part_of_kind(rig, "gland")), wall_mm=fits.wall)
    # the locknut's socket needs its path down to the floor: no boss inside it (the fuse holder's behind it, the
    # cut-off's ahead of it), besides the bodies' own clearance. The bosses may touch the socket's circle: the
    # strip has no room for a gap (1 mm more each side put the cut-off's front into the left fan mount)
    fuse_bosses = _bosses(fuse_pose, fuse.mount_points(), boss_d, boss_h)
    reach = (gland.nut_d_mm + 2 * SOCKET_WALL_MM) / 2 + boss_d / 2     # socket axis to a boss's centre: touching
    gx = max([fuse_pose.t[0] + fuse.size[0] / 2 + clear + gland.nut_d_mm / 2]
             + [bx + _ahead(reach, by - strip_y) for bx, by, *_ in fuse_bosses])
    gland_pose = pose_xyz(gx, strip_y, shell.outer.lo[2])
    cutoff = BoardPart.from_rig(rig, part_of_kind(rig, "cutoff"))
    cut_x = max([gx + gland.nut_d_mm / 2 + clear + cutoff.size[0] / 2]     # mount points: the board's frame,
                + [gx + _ahead(reach, v) - u for u, v, _ in cutoff.mount_points()])   # its centre at 0
    cutoff_pose = pose_xyz(cut_x, strip_y, floor_z + boss_h)
    bosses = _bosses(cutoff_pose, cutoff.mount_points(), boss_d, boss_h)
    breakout = SyncBreakout.from_rig(rig, part_of_kind(rig, "interface_board"))
    rear = cameras.core.bounds().lo[0]
    breakouts = {side: t.pose @ pose_xyz(rear, 0.0, 0.0) for side, t in cameras.thermal.items()}
    return Power(converter=conv, converter_pose=conv_pose, fuse=fuse, fuse_pose=fuse_pose, adapter=adapter,
                 adapter_pose=adapter_pose, battery=battery, battery_pose=battery_pose, battery_mount=mount,
                 gland=gland, gland_pose=gland_pose, cutoff=cutoff, cutoff_pose=cutoff_pose, cutoff_seats=bosses,
                 fuse_bosses=fuse_bosses,
                 breakout=breakout, breakout_poses=breakouts)


def _ahead(reach: float, dy: float) -> float:
    """How far along x two centres ``dy`` apart across must be to stand ``reach`` apart (0 when ``dy`` alone does)."""
    return float(np.sqrt(max(reach * reach - dy * dy, 0.0)))


def _bosses(pose: Pose, points, diameter: float, height: float) -> tuple[Boss, ...]:
    """A boss of the floor under each of a part's mounting points (placed by ``pose``)."""
    return tuple((float(p[0]), float(p[1]), diameter, height) for p in (pose.apply(np.array(pt)) for pt in points))


def _fuse_holder(rig: Rig, fits: Fits) -> FuseHolder:
    """The fuse holder, its tab screws the floor inserts' thread: refused (the rig key named) when its
    mounting names another thread or its tab holes cannot pass that screw."""
    fuse = FuseHolder.from_rig(rig, part_of_kind(rig, "fuse"))
    thread = fits.insert.thread
    key = f"parts.{fuse.part_id}.mounting"
    if fuse.thread is not None and fuse.thread != thread:
        raise DesignError([DesignProblem(key, f"the fuse holder's tabs take {fuse.thread} screws; the floor's inserts "
                                              f"are {thread} (enclosure.insert)")])
    if fuse.hole_d_mm < thread_diameter_mm(thread):
        raise DesignError([DesignProblem(key, f"the fuse holder's {fuse.hole_d_mm:g} mm tab holes do not pass an "
                                              f"{thread} screw")])
    return fuse
