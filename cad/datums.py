"""Camera datums: how each camera is located by features, not friction, and whether those features
remove all six degrees of freedom.

Each camera sits at the end of a chain of *locations* (the Boson in its heat sink, the heat sink on
the thermal bar, the bar on the case floor; the ZED X on its shelf, the ZED mount on the floor). A
location is a set of named *features* (a face, a lip, a stop, a screw in its clearance hole), each a
few point *contacts* with a normal, the mm it may be off along that normal (its play and the position
tolerance of the faces, as named terms) and the degrees of freedom it claims to remove.

A contact at ``p`` with normal ``n`` stops the twist ``(v, w)`` (evaluated at the camera's origin, in
its body axes: x forward, y left, z up) from moving ``p`` along ``n``: the row ``[n, p x n]`` (screw
theory). A location holds its part in all six degrees of freedom when its rows have rank 6; a feature
removes exactly what it claims when, without it, the free motions are the claimed ones (checked by
their rotation axes and the pure translations among them). Pure numpy on the layout's numbers.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from platform_tools.rig.frames import Pose

from .layout import Layout
from .layout.boson_clamp import place_boson_clamps


def clamp_gap_terms(lay: Layout) -> tuple[tuple[str, float, bool], ...]:
    """What may close the retaining plate's gap to the heat sink (mm, each a +- bound): where the machined
    stop sits from the sleeve's rear face (the bore's length), the printed pad's height and its face's form.
    The Boson body's own length tolerance is not known (no vendor drawing): not in it."""
    p = lay.rig.desc.printing.printer
    return (("machined bore length", lay.rig.desc.enclosure.heat_sink.tolerance_mm, True),
            ("printed pad height", p.tolerance_mm, True),
            ("printed face form (half a layer)", p.layer_mm / 2, True))

#: the six degrees of freedom, in the camera body frame (x forward, y left, z up)
DOF = ("x", "y", "z", "roll", "pitch", "yaw")
#: singular values below this (relative to the largest) are a free motion
RANK_TOL = 1e-9


@dataclass(frozen=True)
class Contact:
    """A point contact (rig frame, mm), its unit normal, and the terms (name, +- mm, shared) by which the
    mating face may be off along the normal; a shared term is one value for every contact of its feature
    (where a whole face lands), the others are each contact's own (a face's form, a screw's play)."""
    point: tuple[float, float, float]
    normal: tuple[float, float, float]
    terms: tuple[tuple[str, float, bool], ...]

    def row(self, frame: Pose) -> np.ndarray:
        """The constraint row for twists at ``frame``'s origin, in its axes."""
        inv = frame.inverse()
        p, n = inv.apply(np.asarray(self.point, float)), inv.rotate(np.asarray(self.normal, float))
        return np.concatenate([n, np.cross(p, n)])

    @property
    def worst_mm(self) -> float:
        return float(sum(abs(t) for _, t, _ in self.terms))


@dataclass(frozen=True)
class Feature:
    name: str
    part: str                       # the node that carries the feature
    removes: tuple[str, ...]        # the DOF it claims (names of DOF)
    contacts: tuple[Contact, ...]
    #: a face both parts touch (False: a screw in a hole of ``part``, the other part holds its thread)
    touches_moving: bool = True


@dataclass(frozen=True)
class Clamp:
    """What holds a one-sided feature closed: a part that pushes the located part onto it (the Boson's
    retaining plate onto the front stop). ``contacts``: where it bears on the located part, each normal
    the direction it pushes; ``seat``: the (y, z) extent, in the camera frame, of the face the feature
    bears on, which the push must fall inside (else it tips the part over the seat's edge);
    ``standoff_mm``: the gap it keeps to the base, and ``standoff_terms`` what may close that gap (a
    clamp that lands on the base before it reaches the part presses nothing)."""
    name: str
    part: str
    presses: str                    # the feature it holds closed
    contacts: tuple[Contact, ...]
    seat: tuple[tuple[float, float], tuple[float, float]]
    standoff_mm: float
    standoff_terms: tuple[tuple[str, float, bool], ...]


@dataclass(frozen=True)
class Location:
    """``moving`` located on ``base`` by ``features`` (rig frame); ``frame``: the camera's body pose, the
    axes its free motions are named in; ``clamps``: what keeps its one-sided features closed."""
    name: str
    moving: str
    base: str
    features: tuple[Feature, ...]
    frame: Pose
    clamps: tuple[Clamp, ...] = ()

    def rows(self, without: str | None = None, frame: Pose | None = None) -> np.ndarray:
        f0 = self.frame if frame is None else frame
        return np.array([c.row(f0) for f in self.features if f.name != without for c in f.contacts]).reshape(-1, 6)

    def contacts(self) -> list[Contact]:
        return [c for f in self.features for c in f.contacts]


def free_motions(rows: np.ndarray) -> np.ndarray:
    """(k, 6) a basis of the twists the rows do not stop (empty when the part is held)."""
    if rows.size == 0:
        return np.eye(6)
    _, s, vt = np.linalg.svd(rows)
    rank = int(np.sum(s > RANK_TOL * max(s[0], 1e-300)))
    return vt[rank:]


def _span_rank(m: np.ndarray) -> int:
    if m.size == 0:
        return 0
    s = np.linalg.svd(m, compute_uv=False)
    return int(np.sum(s > 1e-9 * max(s[0], 1e-300))) if s.size and s[0] > 1e-12 else 0


def _in_span(vec: np.ndarray, basis: np.ndarray) -> bool:
    if basis.size == 0:
        return False
    return _span_rank(np.vstack([basis, vec])) == _span_rank(basis)


def describe(twists: np.ndarray) -> list[str]:
    """Names of free motions: the rotation axes their angular parts span, then the pure translations."""
    out = []
    w = twists[:, 3:]
    for k, name in enumerate(DOF[3:]):
        if _in_span(np.eye(3)[k], w):
            out.append(name)
    pure = _pure_translations(twists)
    for k, name in enumerate(DOF[:3]):
        if _in_span(np.eye(3)[k], pure):
            out.append(name)
    if len(out) < len(twists):   # a motion about an axis between the named ones
        out.append(f"{len(twists) - len(out)} combined motion(s)")
    return out


def _pure_translations(twists: np.ndarray) -> np.ndarray:
    """The translations (3-vectors) in the span of ``twists`` (k, 6) that turn about nothing."""
    if twists.size == 0:
        return np.zeros((0, 3))
    w = twists[:, 3:]
    _, s, vt = np.linalg.svd(w.T)        # combinations c with sum c_i w_i = 0
    r = int(np.sum(s > 1e-9)) if s.size else 0
    null = vt[r:]
    return null @ twists[:, :3]


def removes_claimed(loc: Location, f: Feature) -> tuple[bool, str]:
    """Whether taking ``f`` away frees exactly the DOF it claims (by rotation axes and translations)."""
    free = free_motions(loc.rows(without=f.name))
    rot = [d for d in f.removes if d in DOF[3:]]
    trans = [d for d in f.removes if d in DOF[:3]]
    w_rank = _span_rank(free[:, 3:])
    pure = _pure_translations(free)
    ok = (len(free) == len(f.removes) and w_rank == len(rot)
          and all(_in_span(np.eye(3)[DOF.index(d) - 3], free[:, 3:]) for d in rot)
          and all(_in_span(np.eye(3)[DOF.index(d)], pure) for d in trans))
    return ok, ", ".join(describe(free)) or "nothing"


# ----------------------------------------------------------------------------- the rig's locations
def _face(name, part, z, x0, x1, y0, y1, terms, T: Pose, normal=(0.0, 0.0, 1.0), removes=("z", "roll", "pitch")):
    """A planar seat (a box face at ``z`` in frame ``T``) as its four corners (holes in a face's
    middle, such as a screw's access hole, leave its corners)."""
    pts = [(x0, y0, z), (x0, y1, z), (x1, y0, z), (x1, y1, z)]
    return Feature(name, part, removes, tuple(_contact(T, p, normal, terms) for p in pts))


def _contact(T: Pose, p, n, terms) -> Contact:
    """A contact given in frame ``T`` (identity: the rig frame), stored in the rig frame."""
    return Contact(tuple(float(v) for v in T.apply(np.asarray(p, float))),
                   tuple(float(v) for v in T.rotate(np.asarray(n, float))), tuple(terms))


def _screw(T: Pose, axis_point, normal, hole_d: float, terms) -> Contact:
    """A screw bearing on its clearance hole's wall (``hole_d`` across): the contact on the wall behind
    the normal (moving a contact along its normal leaves its row as it is)."""
    p = np.asarray(axis_point, float) - np.asarray(normal, float) * hole_d / 2
    return _contact(T, p, normal, terms)


def _screw_pair(name, part, points, hole_d, play, terms, T: Pose) -> Feature:
    """Two screws in clearance holes (rig frame points, spaced across y): x at both, y at the first."""
    t = (("screw play in its clearance hole", play, False),) + tuple(terms)
    (a, b) = points
    return Feature(name, part, ("x", "y", "yaw"),
                   (_screw(T, a, (1.0, 0, 0), hole_d, t), _screw(T, b, (1.0, 0, 0), hole_d, t),
                    _screw(T, a, (0, 1.0, 0), hole_d, t)), touches_moving=False)


def _joint_heads(lay: Layout, prefix: str, z: float) -> list[tuple[float, float, float]]:
    """Where the screws of the joints named ``prefix*`` cross the plane ``z`` (the seat they locate at)."""
    return [(j.head[0], j.head[1], z) for j in lay.joints if j.name.startswith(prefix)]


def camera_locations(lay: Layout) -> dict[str, tuple[Location, ...]]:
    """Per camera (``zed_x``, ``thermal_left``, ``thermal_right``): its chain of locations from the case
    floor (``case_lower``) up to the camera, each feature's contacts in that camera's body frame."""
    rig = lay.rig
    printer = rig.desc.printing.printer.tolerance_mm
    hs = rig.desc.enclosure.heat_sink
    machined = hs.tolerance_mm
    fits = lay.fits
    m3_hole = fits.screw_hole_mm("M3")
    m3_play = (m3_hole - 3.0) / 2
    layer = rig.desc.printing.printer.layer_mm
    P = ("printed face position", printer, True)            # where the whole face lands
    F = ("printed face form (half a layer)", layer / 2, False)   # each point of it: the layer steps
    H = ("printed hole position", printer, False)           # each hole on its own
    M = ("machined face position", machined, True)
    MH = ("machined hole position", machined, False)
    out = {}
    # ---- ZED X: on its shelf, against its lip, its 1/4-20 screw in the shelf's hole; the mount on the floor
    R = Pose.identity()                  # rig-frame geometry
    T = lay.cameras.zed_pose
    zb, shelf, lip, foot = lay.cameras.zed_box, lay.mounts.zed_shelf, lay.mounts.zed_lip, lay.mounts.zed_foot
    zscrew = next(j for j in lay.joints if j.name.startswith("zed_x_"))
    zplay = (fits.screw_hole_mm(zscrew.thread) - zscrew.diameter_mm) / 2
    sx0, sx1 = max(shelf.lo[0], zb.lo[0]), min(shelf.hi[0], zb.hi[0])
    lip_z = (lip.lo[2] + lip.hi[2]) / 2 if lip.hi[2] <= zb.lo[2] else (zb.lo[2] + lip.hi[2]) / 2
    on_shelf = Location("zed_x on zed_mount", "zed_x", "zed_mount", (
        _face("shelf top face", "zed_mount", shelf.hi[2], sx0, sx1, shelf.lo[1], shelf.hi[1], (P, F), R),
        Feature("rear registration lip", "zed_mount", ("x", "yaw"),
                tuple(_contact(R, (lip.hi[0], y, lip_z), (1.0, 0, 0), (P, F)) for y in (lip.lo[1], lip.hi[1]))),
        Feature("1/4-20 screw in the shelf's hole", "zed_mount", ("y",),
                (_screw(R, (zscrew.head[0], zscrew.head[1], shelf.hi[2]), (0, 1.0, 0),
                        fits.screw_hole_mm(zscrew.thread), (("screw play in its clearance hole", zplay, False), H)),),
                touches_moving=False),
    ), T)
    on_floor = Location("zed_mount on case_lower", "zed_mount", "case_lower", (
        _face("foot on the floor", "case_lower", foot.lo[2], foot.lo[0], foot.hi[0], foot.lo[1], foot.hi[1], (P, F), R),
        _screw_pair("two floor screws in the foot", "case_lower", _joint_heads(lay, "zed_mount_", foot.lo[2])[:2], m3_hole, m3_play,
                    (H,), R),
    ), T)
    out["zed_x"] = (on_floor, on_shelf)
    # ---- each Boson: in its heat sink's bore against the front stop; the heat sink on the bar; the bar on the floor
    bar = lay.mounts.thermal_bar
    play = hs.bore_clearance_mm / 2
    clamps = place_boson_clamps(lay)
    for side, t in lay.cameras.thermal.items():
        T = t.pose
        cb = lay.cameras.core.bounds()          # camera frame
        B = ("bore play (half the diametral clearance)", play, False)
        inboard = cb.lo[1] if t.sign > 0 else cb.hi[1]
        n_in = (0.0, 1.0, 0.0) if t.sign > 0 else (0.0, -1.0, 0.0)
        cl = clamps[side]
        pad = cl.pad
        plate = Clamp("retaining plate", f"boson_clamp_{side}", "front stop ring",
                      tuple(_contact(T, (pad.hi[0], y, z), (1.0, 0, 0), ()) for y in (pad.lo[1], pad.hi[1])
                            for z in (pad.lo[2], pad.hi[2])),
                      ((cb.lo[1], cb.hi[1]), (cb.lo[2], cb.hi[2])), cl.gap_mm, clamp_gap_terms(lay))
        in_bore = Location(f"boson_{side} in heat_sink_{side}", f"boson_{side}", f"heat_sink_{side}", (
            _face("bore floor (flat: clocks the roll)", f"heat_sink_{side}", cb.lo[2], cb.lo[0], cb.hi[0], cb.lo[1],
                  cb.hi[1], (B, M), T),
            Feature("bore side wall (inboard)", f"heat_sink_{side}", ("y", "yaw"),
                    tuple(_contact(T, (x, inboard, 0.0), n_in, (B, M)) for x in (cb.lo[0], cb.hi[0]))),
            Feature("front stop ring", f"heat_sink_{side}", ("x",),
                    (_contact(T, (cb.hi[0], 0.0, (cb.hi[2] + lay.cameras.lens.diameter_mm / 2) / 2), (-1.0, 0, 0),
                              (M,)),)),
        ), T, clamps=(plate,))
        sink = t.heat_sink
        heads = _joint_heads(lay, f"heat_sink_{side}_", sink.lo[2])
        w = hs.wall_mm                          # the base block is as wide as the sleeve (camera frame)
        on_bar = Location(f"heat_sink_{side} on thermal_mount", f"heat_sink_{side}", "thermal_mount", (
            _face("base on the bar", "thermal_mount", cb.lo[2] - w - lay.c.heat_sink_base_mm, cb.lo[0], cb.hi[0],
                  cb.lo[1] - w, cb.hi[1] + w, (P, F, M), T),
            _screw_pair("two screws through the bar", "thermal_mount", heads[:2], m3_hole, m3_play, (H, MH), R),
        ), T)
        bar_floor = Location("thermal_mount on case_lower", "thermal_mount", "case_lower", (
            _face("bar on the floor", "case_lower", bar.lo[2], bar.lo[0], bar.hi[0], bar.lo[1], bar.hi[1], (P, F), R),
            _screw_pair("two floor screws in the bar", "case_lower", _joint_heads(lay, "thermal_mount_", bar.lo[2])[:2],
                        m3_hole, m3_play, (H,), R),
        ), T)
        out[f"thermal_{side}"] = (bar_floor, on_bar, in_bore)
    return out


def clamp_problems(loc: Location, cl: Clamp) -> tuple[list[str], str]:
    """(problems, detail) of one clamp: it must press its feature's contacts shut (its push against their
    normals), inside the seat, and keep a standoff to the base that what may close it cannot close."""
    bad = []
    target = next((f for f in loc.features if f.name == cl.presses), None)
    if target is None:
        return [f"{loc.name}: {cl.name} presses {cl.presses!r}, which is no feature of it"], ""
    inv = loc.frame.inverse()
    push = sum(np.asarray(c.normal, float) for c in cl.contacts)
    push = push / max(np.linalg.norm(push), 1e-12)
    along = min(-float(push @ np.asarray(c.normal, float)) for c in target.contacts)
    if along <= 1e-9:
        bad.append(f"{loc.name}: {cl.name} ({cl.part}) does not press {loc.moving} onto the {cl.presses}: it pushes "
                   f"along {np.round(inv.rotate(push), 3).tolist()} (camera frame)")
    centre = np.mean([inv.apply(np.asarray(c.point, float)) for c in cl.contacts], axis=0)
    (y0, y1), (z0, z1) = cl.seat
    if not (y0 <= centre[1] <= y1 and z0 <= centre[2] <= z1):
        bad.append(f"{loc.name}: {cl.name} pushes at y {centre[1]:.1f}, z {centre[2]:.1f} mm (camera frame), outside "
                   f"the {cl.presses}'s seat (y {y0:g} to {y1:g}, z {z0:g} to {z1:g}): it tips {loc.moving} over its edge")
    worst = sum(abs(v) for _, v, _ in cl.standoff_terms)
    if worst >= cl.standoff_mm - 1e-9:
        bad.append(f"{loc.name}: {cl.name} keeps {cl.standoff_mm:g} mm off {loc.base}, and "
                   + " + ".join(f"{n} {v:g}" for n, v, _ in cl.standoff_terms)
                   + f" = {worst:g} mm may close it: it can land on {loc.base} before it presses {loc.moving}")
    detail = (f"{loc.name}: {cl.name} ({cl.part}) holds the {cl.presses} closed: pushes at y {centre[1]:.1f}, "
              f"z {centre[2]:.1f} mm inside its seat; {cl.standoff_mm:g} mm off {loc.base}, at most {worst:.2f} mm "
              f"of it may close")
    return bad, detail


def datum_problems(locations: dict[str, tuple[Location, ...]]) -> tuple[list[str], list[str]]:
    """(problems, details): a location with a free motion, a feature that does not remove what it claims,
    a clamp that does not hold its feature closed (:func:`clamp_problems`)."""
    bad, details = [], []
    for cam, chain in locations.items():
        for loc in chain:
            for cl in loc.clamps:
                b, d = clamp_problems(loc, cl)
                bad += [f"{cam}: {x}" for x in b]
                details += [f"{cam}: {d}"] if d else []
            free = free_motions(loc.rows())
            if len(free):
                bad.append(f"{cam}: {loc.name}: free to move ({', '.join(describe(free))}): add a datum feature")
            for f in loc.features:
                ok, freed = removes_claimed(loc, f)
                line = f"{cam}: {loc.name}: {f.name} ({f.part}) removes {', '.join(f.removes)}"
                details.append(line + ("" if ok else f"  <-- without it {freed} is free"))
                if not ok and not len(free):
                    bad.append(f"{cam}: {loc.name}: {f.name} claims {', '.join(f.removes)}; without it {freed} "
                               f"is free")
    return bad, details


def contact_gaps(locations: dict[str, tuple[Location, ...]], distance) -> list[tuple[str, str, str, float]]:
    """(camera, feature, node, gap mm) for every contact and each part it must lie on: the carrier, and
    the moving part for a face both touch; ``distance(node, point)`` measures the built geometry."""
    out = []
    for cam, chain in locations.items():
        for loc in chain:
            for f in loc.features:
                for c in f.contacts:
                    nodes = [f.part] + ([loc.moving] if f.touches_moving else [])
                    out += [(cam, f"{loc.name}: {f.name}", node, float(distance(node, c.point))) for node in nodes]
            for cl in loc.clamps:     # a clamp bears on the part it holds: its contacts on both
                for c in cl.contacts:
                    out += [(cam, f"{loc.name}: {cl.name}", node, float(distance(node, c.point)))
                            for node in (cl.part, loc.moving)]
    return out
