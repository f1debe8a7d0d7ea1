"""The Boson's retaining plate: a printed L-shaped plate behind each core that holds it forward against
its heat sink's front stop (the camera's axial datum, cad/datums.py).

Camera frame (x forward along the optical axis, y left, z up; the core's rear face at ``rear``). Behind
each heat sink, 2 mm back (``enclosure.heat_sink_gap_mm``), the fan's printed plate covers the outboard
strip of the core's rear face from the floor up, and the sync breakout board covers its middle; what is
left is the inboard strip and the copper base under the sleeve. So each plate (mirror images, left and
right) has:

- an inboard **leg** whose **pad** bears on the core's rear face beside the breakout, ``CLAMP_GAP_MM``
  proud of the plate: the plate itself stays that far behind the heat sink's rear face, so the screws
  can only close the pad onto the camera, never the plate onto the copper (the gap against what may
  close it: cad/datums.py ``clamp_gap_terms``, checked by the camera-datums check);
- one M1.6 screw through the pad into the core's inboard rear M1.6 hole (``parts.<boson>.mounting``,
  face rear; the outboard hole is 2 mm in front of the fan plate, no room for a head): plate and camera
  one piece;
- a **foot** across the copper base with two M1.6 screws into tapped holes in the base's rear face,
  which pull that piece forward until the core's front face sits on the stop.

The anchors' clearance holes leave the plate more play across the axis than the bore leaves the camera
(``anchor_play_mm`` vs. half of ``enclosure.heat_sink.bore_clearance_mm``), so the plate clamps along the
axis only: the bore still locates y, z, roll (its flat floor clocks the square body), pitch and yaw. The
pad's push lies inside the core's front face, where the stop ring bears: the camera is pressed onto the
stop, not tipped over its edge (checked in cad/datums.py).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from cad.bought.base import envelope, part_of_kind
from cad.bought.fasteners import Screw, fastener_table, pick_length
from cad.geom import Bounds, Vec3, placed_bounds

from .constants import HOLE_LEAD_MM
from .constraints import DesignError, DesignProblem
from .joints import TAP_DRILL_RUNOUT_MM, Hole, Joint
from .rig_layout import Layout

#: the thread of every screw of the plate: the Boson's own rear holes are M1.6
CLAMP_THREAD = "M1.6"
#: the plate's thickness behind its pad (along x)
CLAMP_PLATE_MM = 3.0
#: how far the pad stands proud of the plate: the plate's gap to the heat sink's rear face
CLAMP_GAP_MM = 1.0
#: the anchor screws, across the camera (y, from the axis): inside the base's two M3 holes (12 mm apart),
#: under the breakout board
CLAMP_ANCHOR_Y_MM = 3.0
#: the thread the anchors cut into the copper base (along x, from its rear face)
CLAMP_ANCHOR_DEPTH_MM = 4.0
#: the leg rises this far above the core's rear hole (a screw head's width: room for the head on the leg)
CLAMP_LEG_ABOVE_HOLE_MM = 3.0
#: the core screw engages at least this share of the core's rear hole (its depth is an estimate)
CORE_THREAD_MIN_ENGAGEMENT = 0.6


class ClampError(DesignError):
    """The retaining plate cannot be made from these values: bad input, naming the rig keys (exit 2)."""

    def __init__(self, key: str, message: str):
        super().__init__([DesignProblem(key, message)])


@dataclass(frozen=True)
class BosonClamp:
    """The plate of one camera, in the camera frame (mm)."""
    side: str
    leg: Bounds                         # the inboard leg, beside the breakout
    foot: Bounds                        # across the copper base, under the breakout, clear of the fan plate
    pad: Bounds                         # on the core's rear face, proud of the leg
    core_screw: Vec3                    # the core's inboard rear M1.6 hole, on its rear face
    anchors: tuple[Vec3, Vec3]          # the anchors' tapped holes, on the heat sink's rear face
    gap_mm: float                       # the plate's gap to the heat sink's rear face
    anchor_play_mm: float               # radial play of an anchor in its clearance hole
    ligament_mm: float                  # material between the core screw's hole and the breakout's side

    @property
    def rear_x(self) -> float:
        """The core's rear face (camera frame x): where the pad bears."""
        return self.pad.hi[0]

    @property
    def head_x(self) -> float:
        """Where every screw head sits: the plate's back face."""
        return self.leg.lo[0]

    @property
    def blocks(self) -> tuple[Bounds, ...]:
        return (self.leg, self.foot, self.pad)


def place_boson_clamps(lay: Layout) -> dict[str, BosonClamp]:
    """Each camera's plate from the core's rear holes, the breakout's width, the heat sink's base and the
    fan plate behind it. Raises :class:`ClampError` (a :class:`DesignError`) naming the rig key when it
    cannot be made."""
    rig, fits, cams = lay.rig, lay.fits, lay.cameras
    hs = rig.desc.enclosure.heat_sink
    cb = cams.core.bounds()
    rear = cb.lo[0]
    holes = [m for m in rig.part(cams.core.part_id).mounting if m.face.value == "rear" and m.thread == CLAMP_THREAD]
    key = f"parts.{cams.core.part_id}.mounting"
    if not holes or len(holes[0].positions_mm) != 2 or {p[0] > 0 for p in holes[0].positions_mm} != {True, False}:
        raise ClampError(key, f"the retaining plate needs two {CLAMP_THREAD} holes on the core's rear face, one "
                              "either side of its axis")
    sliding = rig.desc.printing.fits.sliding_mm
    hole_d = fits.screw_hole_mm(CLAMP_THREAD)
    thread_d = fastener_table().size(CLAMP_THREAD).diameter_mm
    head_d = rig.dim(fastener_table().size(CLAMP_THREAD).screw, "head_diameter_mm")
    bid = part_of_kind(rig, "interface_board")
    win_y = envelope(rig, bid)[1] / 2 + sliding           # the leg's inner edge: a sliding fit beside the breakout
    side_y = cb.hi[1] - sliding                           # its outer edge: inside the bore's outline, on the camera only
    bottom = cb.lo[2] - hs.wall_mm - lay.c.heat_sink_base_mm     # the copper base's underside
    anchor_z = bottom + lay.c.heat_sink_base_mm / 2
    back, front = rear - CLAMP_GAP_MM - CLAMP_PLATE_MM, rear - CLAMP_GAP_MM
    out = {}
    for side, t in cams.thermal.items():
        inboard = -t.sign                                 # the inboard direction, camera y
        y, z = next((float(p[0]), float(p[1])) for p in holes[0].positions_mm if p[0] * inboard > 0)
        ligament = abs(y) - hole_d / 2 - win_y
        if ligament < fits.min_wall - 1e-9:
            raise ClampError(f"parts.{bid}.envelope_mm.y", f"the {2 * (win_y - sliding):g} mm breakout board leaves the "
                             f"retaining plate {ligament:.2f} mm between it and the {hole_d:g} mm hole for the core's "
                             f"rear {CLAMP_THREAD} screw at y = {y:g} mm ({key}); the printer's thinnest wall is "
                             f"{fits.min_wall:g} mm")
        top = z + CLAMP_LEG_ABOVE_HOLE_MM
        lo_y, hi_y = sorted((inboard * win_y, inboard * side_y))
        leg = Bounds((back, lo_y, bottom), (front, hi_y, top))
        pad = Bounds((front, lo_y, cb.lo[2] + sliding), (rear, hi_y, top))
        # the foot reaches outboard up to the fan plate, less the clearance
        fan = placed_bounds(lay.cooling.plates[side].plate, t.pose.inverse())     # in the camera frame
        fan_y = min(abs(fan.lo[1]), abs(fan.hi[1]))
        out_y = -inboard * min(side_y, fan_y - fits.clear)
        foot_top = cb.lo[2] - sliding
        f_lo, f_hi = sorted((inboard * side_y, out_y))
        foot = Bounds((back, f_lo, bottom), (front, f_hi, foot_top))
        anchors = ((rear, CLAMP_ANCHOR_Y_MM, anchor_z), (rear, -CLAMP_ANCHOR_Y_MM, anchor_z))
        for a in anchors:
            if not (foot.lo[1] + head_d / 2 <= a[1] <= foot.hi[1] - head_d / 2):
                raise ClampError("enclosure.component_clearance_mm", f"the retaining plate's foot ({foot.lo[1]:.1f} "
                                 f"to {foot.hi[1]:.1f} mm across the camera, kept {fits.clear:g} mm off the fan plate) "
                                 f"has no room for an anchor head at y = {a[1]:g} mm")
        out[side] = BosonClamp(side=side, leg=leg, foot=foot, pad=pad, core_screw=(rear, y, z), anchors=anchors,
                               gap_mm=CLAMP_GAP_MM, anchor_play_mm=(hole_d - thread_d) / 2, ligament_mm=ligament)
    return out


def clamp_joints(lay: Layout, clamps: dict[str, BosonClamp] | None = None) -> tuple[Joint, ...]:
    """Per camera, the screw into the core (``boson_clamp_<side>_core``) and the two into the heat sink
    (``boson_clamp_<side>_anchor_<k>``), in the rig frame: heads on the plate's back face, driven forward
    along the optical axis."""
    rig, fits = lay.rig, lay.fits
    clamps = clamps or place_boson_clamps(lay)
    size = fastener_table().size(CLAMP_THREAD)
    core_depth = next(m for m in rig.part(lay.cameras.core.part_id).mounting if m.face.value == "rear").depth_mm
    hole_d = fits.screw_hole_mm(CLAMP_THREAD)
    out = []
    for side, t in lay.cameras.thermal.items():
        cl = clamps[side]
        grip = cl.rear_x - cl.head_x
        fwd = tuple(float(v) for v in t.pose.rotate(np.array([1.0, 0.0, 0.0])))
        dv = np.asarray(fwd)

        def joint(name, on_rear: Vec3, host: str, depth: float, cut_host: str | None) -> Joint:
            length = pick_length(grip, min(lay.c.tapped_engagement_min_mm, depth * CORE_THREAD_MIN_ENGAGEMENT), depth)
            head = t.pose.apply(np.array([cl.head_x, on_rear[1], on_rear[2]]))
            holes = (Hole(f"boson_clamp_{side}", tuple(head - HOLE_LEAD_MM * dv), fwd, hole_d, grip + 2 * HOLE_LEAD_MM),)
            if cut_host:    # a thread we cut ourselves: the table's tap drill, run past the thread
                holes += (Hole(cut_host, tuple(head + (grip - HOLE_LEAD_MM) * dv), fwd, size.tap_drill_mm,
                               depth + HOLE_LEAD_MM + TAP_DRILL_RUNOUT_MM),)
            return Joint(name=name, screw=Screw.from_rig(rig, size.screw, CLAMP_THREAD, length),
                         head=tuple(float(v) for v in head), direction=fwd, grip_mm=grip, kind="tapped", host=host,
                         holes=holes)
        out.append(joint(f"boson_clamp_{side}_core", cl.core_screw, f"boson_{side}", core_depth, None))
        for k, p in enumerate(cl.anchors):
            out.append(joint(f"boson_clamp_{side}_anchor_{k}", p, f"heat_sink_{side}", CLAMP_ANCHOR_DEPTH_MM,
                             f"heat_sink_{side}"))
    return tuple(out)


def with_boson_clamps(lay: Layout) -> Layout:
    """The layout with the retaining plates' screws among its joints (so their holes are cut, the BOM
    counts them and the assembly-order check drives them)."""
    if any(j.name.startswith("boson_clamp_") for j in lay.joints):
        return lay
    return replace(lay, joints=lay.joints + clamp_joints(lay))
