"""Dimensioned drawings (issue 16): every printed part and the heat sink, read back as SVG; the numbers on
them equal the sizes measured on the part's STEP read back by OpenCascade, and the lines drawn agree
with the numbers at the sheet's scale.

Hole positions (issue 16, G4): every hole of the hole table has an id on its view and a row with its
ordinates from the view's datum corner; the tests read those rows from the SVG and find the holes again
on the part's STL with trimesh (sections across each axis, the circular loops of each section: numpy and
trimesh, no call into cad/drawings.py's B-rep code), both ways: every row is a hole of the mesh and every
hole of the mesh is a row. The heat sink's tapped-hole spacing equals the joints' within 0.01 mm with the
stack-up's tolerance, and a hole moved in the model (a modified part, a ``--set`` override) moves the
number on the drawing."""
from __future__ import annotations

import dataclasses
import xml.etree.ElementTree as ET
from collections import defaultdict

import cadquery as cq
import numpy as np
import pytest

from cad.drawings import VIEWS, drawing, scale_of, write_drawings

pytestmark = pytest.mark.slow
NS = {"s": "http://www.w3.org/2000/svg"}
#: the view a hole is seen end-on in -> (the axis it runs along, the view's two paper axes)
VIEW_AXES = {"plan": (2, (0, 1)), "elevation": (1, (0, 2)), "side": (0, (1, 2))}
#: the STL is written as ``build.py export`` writes it, in the part's own frame, at these tolerances (mm, rad)
STL_TOL, STL_ANGULAR = 0.01, 0.05
#: a hole found on the mesh is the row's when its centre is this close (mm) and its diameter this close (mm)
POS_TOL_MM, DIA_TOL_MM = 0.02, 0.03


@pytest.fixture(scope="module")
def drawings(asm, tmp_path_factory):
    folder = tmp_path_factory.mktemp("drawings")
    return folder, write_drawings(asm, folder)


def _dims(root) -> dict[tuple[str, str], float]:
    return {(t.get("data-view"), t.get("data-dim")): float(t.get("data-value"))
            for t in root.iterfind(".//s:text[@class='dim']", NS) if t.get("data-view")}


def _text(t) -> str:
    return "".join(t.itertext())


def _rows(root) -> list[dict]:
    """The position table's rows: id, view, ordinates (mm), diameter, depth, tolerance, what it is for."""
    out = []
    for t in root.iterfind(".//s:text[@class='hole-pos']", NS):
        out.append(dict(id=t.get("data-id"), view=t.get("data-hole-view"),
                        at=tuple(float(v) for v in t.get("data-at").split()), d=float(t.get("data-diameter")),
                        depth=float(t.get("data-depth")), tol=float(t.get("data-tolerance")), purpose=t.get("data-for"),
                        on_solid=t.get("data-on-solid") == "1", text=_text(t)))
    return out


def test_every_made_part_has_a_drawing(asm, drawings):
    folder, paths = drawings
    assert sorted(p.name for p in paths) == sorted(f"{pid}.drawing.svg" for pid in asm.printed())


def test_dimensions_equal_the_step_read_back(asm, drawings, tmp_path):
    folder, _ = drawings
    for pid, n in asm.printed().items():
        root = ET.parse(folder / f"{pid}.drawing.svg").getroot()
        dims = _dims(root)
        step = tmp_path / f"{pid}.step"
        cq.exporters.export(n.local_shape(asm.cache), str(step), "STEP")
        bb = cq.importers.importStep(str(step)).val().BoundingBox()
        # OCC's box of a re-read STEP may be up to ~0.01 mm loose; the HLR outline is exact
        want = {"x": bb.xlen, "y": bb.ylen, "z": bb.zlen}
        assert {k for _, k in dims} == {"x", "y", "z"}, pid
        for (view, axis), v in dims.items():
            assert v == pytest.approx(want[axis], abs=0.03), (pid, view, axis)
        # the text says the tolerance of the part's process
        tol = asm.rig.desc.enclosure.heat_sink.tolerance_mm if n.category == "machined" else \
            asm.rig.desc.printing.printer.tolerance_mm
        assert all(t.text.endswith(f"±{tol:g}") for t in root.iterfind(".//s:text[@data-view]", NS)), pid


def test_lines_drawn_at_the_sheet_scale(asm, drawings):
    folder, _ = drawings
    for pid in ("case_lid", "heat_sink", "zed_mount"):
        text = (folder / f"{pid}.drawing.svg").read_text()
        s = scale_of(text)
        root = ET.fromstring(text)
        dims = _dims(root)
        for view in VIEWS:
            g = root.find(f".//s:g[@id='view-{view}']", NS)
            pts = np.array([[float(a) for a in p.split(",")] for pl in g.iterfind("s:polyline", NS)
                            for p in pl.get("points").split()])
            width_px, height_px = np.ptp(pts[:, 0]), np.ptp(pts[:, 1])
            ax, ay = {"plan": "xy", "elevation": "xz", "side": "yz"}[view]
            assert width_px / s == pytest.approx(dims[(view, ax)], abs=0.05), (pid, view)
            assert height_px / s == pytest.approx(dims[(view, ay)], abs=0.05), (pid, view)


def test_heat_sink_drawing_gives_the_bore_and_holes(asm, rig, drawings):
    folder, _ = drawings
    root = ET.parse(folder / "heat_sink.drawing.svg").getroot()
    feats = {t.get("data-label"): float(t.get("data-value")) for t in root.iterfind(".//s:text[@data-label]", NS)}
    env = rig.part(rig.desc.sensors.thermal.part).envelope_mm
    assert feats["bore width"] == pytest.approx(env.y.value) and feats["bore height"] == pytest.approx(env.z.value)
    assert feats["fin height"] == rig.desc.enclosure.heat_sink.fin_height_mm
    holes = [_text(t) for t in root.iterfind(".//s:text[@class='hole']", NS)]
    assert any("tap drill, then tap M3" in h and "2 off" in h for h in holes), holes


def test_case_lower_drawing_lists_the_gland_hole(asm, drawings):
    folder, _ = drawings
    root = ET.parse(folder / "case_lower.drawing.svg").getroot()
    holes = [_text(t) for t in root.iterfind(".//s:text[@class='hole']", NS)]
    d = asm.layout.power.gland.hole_d_mm
    assert any(h.startswith(f"Ø{d:g} x") and "cable gland" in h for h in holes), holes


# ---------------------------------------------------------------------------- hole positions, from the STL
def _loops(segments: np.ndarray) -> list[np.ndarray]:
    """The closed polylines a plane section's segments (n, 2, 2) make (their endpoints joined where equal)."""
    key = lambda p: (round(float(p[0]), 5), round(float(p[1]), 5))
    nbr: dict = defaultdict(list)
    for a, b in segments:
        ka, kb = key(a), key(b)
        if ka != kb:
            nbr[ka].append(kb)
            nbr[kb].append(ka)
    seen, out = set(), []
    for start in list(nbr):
        if start in seen:
            continue
        loop, prev, cur = [start], None, start
        seen.add(start)
        while True:
            nxt = [q for q in nbr[cur] if q != prev and (q not in seen or (q == start and len(loop) > 2))]
            if not nxt:
                break
            prev, cur = cur, nxt[0]
            if cur == start:
                out.append(np.array(loop))
                break
            seen.add(cur)
            loop.append(cur)
    return out


def _inside(pt, poly: np.ndarray) -> bool:
    x, y = pt
    xs, ys = poly[:, 0], poly[:, 1]
    xj, yj = np.roll(xs, 1), np.roll(ys, 1)
    cross = ((ys > y) != (yj > y)) & (x < (xj - xs) * (y - ys) / (yj - ys + 1e-300) + xs)
    return bool(np.count_nonzero(cross) % 2)


def mesh_holes(mesh) -> tuple[list[tuple[int, tuple[float, float], float]], list[np.ndarray]]:
    """Every round hole of ``mesh`` along a part axis: (axis, centre in the other two axes, diameter), one
    entry per distinct hole; and per axis every section point (m, 2). Sections midway between the levels
    of the mesh's flat faces across each axis (a hole along an axis ends on such faces); a hole is a
    section loop whose points are all one radius from their mean, inside an odd number of the section's
    other loops (material around it)."""
    import trimesh
    found: list[tuple[int, tuple[float, float], float]] = []
    points: list[np.ndarray] = []
    for k in range(3):
        pts = []
        other = [i for i in range(3) if i != k]
        flat = np.abs(mesh.face_normals[:, k]) > 0.9999
        levels = np.unique(np.round(mesh.triangles[flat][:, :, k].ravel(), 2))
        for lo, hi in zip(levels[:-1], levels[1:]):
            if hi - lo < 0.05:
                continue
            segs = trimesh.intersections.mesh_plane(mesh, np.eye(3)[k], np.eye(3)[k] * (lo + hi) / 2)
            if len(segs) == 0:
                continue
            pts.append(segs[:, :, other].reshape(-1, 2))
            loops = _loops(segs[:, :, other])
            for n, lp in enumerate(loops):
                if len(lp) < 12:
                    continue
                c = lp.mean(axis=0)
                r = np.hypot(*(lp - c).T)
                if r.max() - r.min() > 0.02 or r.mean() < 0.3:
                    continue
                depth = sum(_inside(lp[0], q) for m, q in enumerate(loops) if m != n and len(q) > 2)
                if depth % 2 == 0:
                    continue                      # an outer boundary (a boss, a standoff): not a hole
                d = 2 * float(r.mean())
                if not any(f[0] == k and abs(f[2] - d) < DIA_TOL_MM and np.hypot(*(np.array(f[1]) - c)) < POS_TOL_MM
                           for f in found):
                    found.append((k, (float(c[0]), float(c[1])), d))
        points.append(np.concatenate(pts) if pts else np.zeros((0, 2)))
    return found, points


def arc_centre(points: np.ndarray, c, d: float) -> tuple[np.ndarray, float] | None:
    """A hole the part's outline cuts open (no closed loop in any section: a counterbore through a gusset):
    the section points within 0.03 mm of the circle of diameter ``d`` about ``c``, when they go at least a
    quarter round it, and the least-squares circle through them (Kasa): (its centre, its diameter)."""
    q = points[np.abs(np.hypot(*(points - c).T) - d / 2) < 0.03]
    if len(q) < 8:
        return None
    ang = np.sort(np.arctan2(q[:, 1] - c[1], q[:, 0] - c[0]))
    gaps = np.diff(np.concatenate([ang, ang[:1] + 2 * np.pi]))
    if 2 * np.pi - gaps.max() < np.pi / 2:
        return None
    A = np.column_stack([2 * q, np.ones(len(q))])
    (cx, cy, e), *_ = np.linalg.lstsq(A, (q ** 2).sum(axis=1), rcond=None)
    return np.array([cx, cy]), 2 * float(np.sqrt(e + cx * cx + cy * cy))


def _stl(asm, node, path):
    import trimesh
    cq.exporters.export(node.local_shape(asm.cache), str(path), "STL", tolerance=STL_TOL, angularTolerance=STL_ANGULAR)
    return trimesh.load(str(path))


def test_hole_positions_equal_the_holes_of_the_stl(asm, drawings, tmp_path):
    """Both ways on every part: each row's hole (its view's axis, its ordinates from the mesh's own lowest
    corner, its diameter) is a round hole of the STL, and each round hole of the STL is a row. Without
    the change: no part has a position row (``rows`` empty: the drawings gave diameter, depth and count only)."""
    pytest.importorskip("trimesh")
    folder, _ = drawings
    total, opened = 0, []
    for pid, n in asm.printed().items():
        rows = _rows(ET.parse(folder / f"{pid}.drawing.svg").getroot())
        assert rows, f"{pid}: no hole positions on the drawing"
        mesh = _stl(asm, n, tmp_path / f"{pid}.stl")
        lo = mesh.bounds[0]
        holes, points = mesh_holes(mesh)
        claimed = []
        for r in rows:
            k, (i, j) = VIEW_AXES[r["view"]]
            claimed.append((k, (lo[i] + r["at"][0], lo[j] + r["at"][1]), r["d"], r["id"]))
        for k, c, d, hid in claimed:
            near = [h for h in holes if h[0] == k and abs(h[2] - d) < DIA_TOL_MM
                    and np.hypot(c[0] - h[1][0], c[1] - h[1][1]) < POS_TOL_MM]
            if not near:                          # cut open by the outline: the arc it leaves
                arc = arc_centre(points[k], np.asarray(c), d)
                near = arc is not None and np.hypot(*(arc[0] - c)) < POS_TOL_MM and abs(arc[1] - d) < DIA_TOL_MM
                opened.append(f"{pid} {hid}")
            assert near, (f"{pid} {hid}: no Ø{d:.2f} hole along {'xyz'[k]} at {np.round(c, 3).tolist()} on the STL; "
                          f"nearest {sorted(holes, key=lambda h: np.hypot(c[0] - h[1][0], c[1] - h[1][1]))[:1]}")
        for k, c, d in holes:
            mine = [h for h in claimed if h[0] == k and abs(h[2] - d) < DIA_TOL_MM
                    and np.hypot(c[0] - h[1][0], c[1] - h[1][1]) < POS_TOL_MM]
            assert mine, f"{pid}: the STL's Ø{d:.2f} hole along {'xyz'[k]} at {np.round(c, 3).tolist()} is not on the drawing"
        total += len(rows)
    assert total > 80
    print(f"{total} holes; cut open (found by their arcs): {opened}")


def test_every_hole_has_an_id_on_its_view(drawings):
    """Each row's id is written once on the view the row names, beside a marker at the row's ordinates
    (the sheet's scale from the view's datum corner). Without the change: no ids, no rows."""
    folder, paths = drawings
    for path in paths:
        text = path.read_text()
        root, s = ET.fromstring(text), scale_of(text)
        rows = {r["id"]: r for r in _rows(root)}
        assert rows, f"{path.name}: no hole rows"
        shown: dict[str, str] = {}
        for view in VIEWS:
            g = root.find(f".//s:g[@id='holes-{view}']", NS)
            if g is None:
                continue
            for t in g.iterfind("s:text[@class='hole-id']", NS):
                assert float(t.get("y")) > 0 and _text(t) == "/".join(t.get("data-ids").split())
                for i in t.get("data-ids").split():
                    assert i not in shown, (path.name, i)
                    shown[i] = view
            # every marker sits at its row's ordinates from the view's outline corner, at the sheet's scale
            pts = np.array([[float(a) for a in p.split(",")] for pl in root.find(f".//s:g[@id='view-{view}']", NS)
                            .iterfind("s:polyline", NS) for p in pl.get("points").split()])
            x0, y1 = pts[:, 0].min(), pts[:, 1].max()
            for c in g.iterfind("s:circle", NS):
                r = rows[c.get("data-hole")]
                assert float(c.get("cx")) == pytest.approx(x0 + r["at"][0] * s, abs=0.05), (path.name, r["id"])
                assert float(c.get("cy")) == pytest.approx(y1 - r["at"][1] * s, abs=0.05), (path.name, r["id"])
        assert shown == {i: r["view"] for i, r in rows.items()}, path.name


def _joint_hole_words(asm) -> dict[str, dict[float, set[str]]]:
    """Per part, per hole diameter, what the joints say the hole is (read off each joint's kind and host
    here, not through cad/drawings.py): an insert's, a tapped hole's, a clearance or a head hole."""
    lay = asm.layout
    part_of = {n.name: n.part_id for n in asm.nodes}
    out: dict = defaultdict(lambda: defaultdict(set))
    for j in lay.joints:
        clr = lay.fits.screw_hole_mm(j.thread)
        for h in j.holes:
            pid = part_of.get(h.part, h.part)
            if h.part == j.host:
                word = {"insert": "insert", "tapped": "tap", "self_tap": "pilot"}[j.kind]
            elif abs(h.diameter - clr) < 1e-9:
                word = "clearance"
            else:
                word = "head"
            out[pid][round(h.diameter, 2)].add(f"{word}|{j.thread.split()[0]}")
    return out


def test_every_hole_says_what_it_is_for(asm, drawings):
    """The joints' holes say insert / tap / pilot / clearance / head with their thread; case_lower's Ø10.3
    (the ZED screw's access hole, 1/4-20) and zed_mount's Ø6.85 (the 1/4-20 clearance) are named; the gland
    says so. Without the change: those two rows had no label at all ('Ø10.3 x 2.4 deep, 1 off')."""
    folder, _ = drawings
    words = _joint_hole_words(asm)
    for pid in asm.printed():
        for r in _rows(ET.parse(folder / f"{pid}.drawing.svg").getroot()):
            want = words[pid].get(round(r["d"], 2))
            if want:
                assert any(w in r["purpose"] and t in r["purpose"] for w, t in (x.split("|") for x in want)), (pid, r)
            assert r["on_solid"], (pid, r)
            assert r["purpose"] and r["purpose"] in r["text"]
    lower = _rows(ET.parse(folder / "case_lower.drawing.svg").getroot())
    zed = _rows(ET.parse(folder / "zed_mount.drawing.svg").getroot())
    zs = next(j for j in asm.layout.joints if j.name.startswith("zed_x_"))
    access = [r for r in lower if r["d"] == pytest.approx(10.3)]
    assert access and all("access" in r["purpose"] and "1/4-20" in r["purpose"] for r in access), access
    clr = [r for r in zed if r["d"] == pytest.approx(asm.layout.fits.screw_hole_mm(zs.thread))]
    assert clr and all(r["purpose"].startswith("clearance 1/4-20") for r in clr), clr
    assert [r["purpose"] for r in lower if r["d"] == pytest.approx(asm.layout.power.gland.hole_d_mm)] == ["cable gland"]


def _model_spacing(asm) -> tuple[float, np.ndarray]:
    """The heat sink screws' spacing and their midpoint (camera frame), from the joints' heads."""
    t = asm.layout.cameras.thermal["left"]
    heads = [t.pose.inverse().apply(np.asarray(j.head, float)) for j in asm.layout.joints
             if j.name.startswith("heat_sink_left_")]
    assert len(heads) == 2
    return float(np.linalg.norm((heads[0] - heads[1])[:2])), (heads[0] + heads[1]) / 2


def _stack_up_hole_tolerance(asm) -> float:
    """The +- the stack-up's "two screws through the bar" feature gives each machined hole's position."""
    from cad.datums import camera_locations
    on_bar = next(loc for loc in camera_locations(asm.layout)["thermal_left"] if loc.moving == "heat_sink_left")
    f = next(f for f in on_bar.features if f.name == "two screws through the bar")
    return next(v for c in f.contacts for name, v, _ in c.terms if name == "machined hole position")


def _spacing(root) -> ET.Element:
    return root.find(".//s:text[@data-dim='hole-spacing']", NS)


def test_heat_sink_hole_spacing_and_bore_position(asm, drawings):
    """The tapped holes' spacing dimension equals the joints' (12 mm on the default rig) within 0.01 mm
    with the stack-up's hole position tolerance (not the printer's); the bore is placed from the holes'
    midpoint as the layout places the Boson. Without the change: no spacing dimension (None) and no
    bore position rows (KeyError)."""
    folder, _ = drawings
    root = ET.parse(folder / "heat_sink.drawing.svg").getroot()
    spacing, mid = _model_spacing(asm)
    dim = _spacing(root)
    assert dim is not None, "no hole spacing on the heat sink's drawing"
    assert float(dim.get("data-value")) == pytest.approx(spacing, abs=0.01)
    tol = _stack_up_hole_tolerance(asm)
    assert tol != asm.rig.desc.printing.printer.tolerance_mm
    assert float(dim.get("data-tolerance")) == tol and _text(dim).startswith(f"{spacing:.2f} ±{tol:g}")
    a, b = dim.get("data-holes").split()
    rows = {r["id"]: r for r in _rows(root)}
    assert {rows[a]["purpose"], rows[b]["purpose"]} == {"tap M3 (tap drill)"}
    assert np.hypot(*np.subtract(rows[a]["at"], rows[b]["at"])) == pytest.approx(spacing, abs=0.01)
    feats = {t.get("data-label"): float(t.get("data-value")) for t in root.iterfind(".//s:text[@data-label]", NS)}
    bore = asm.layout.cameras.core.bounds()          # the bore is the Boson body (camera frame)
    assert feats[f"bore centre from the {a}-{b} midpoint, x"] == pytest.approx(bore.centre[0] - mid[0], abs=0.01)
    assert feats[f"bore centre from the {a}-{b} midpoint, y"] == pytest.approx(bore.centre[1] - mid[1], abs=0.01)


def _heat_sink_with(asm, holes, build=None):
    node = asm.printed()["heat_sink"]
    spec = dataclasses.replace(node.spec, holes=holes)
    if build is not None:
        spec = build(spec)
    return dataclasses.replace(node, spec=spec, _shape=None)


def test_a_moved_hole_moves_the_drawing(asm):
    """A heat sink whose first M3 tapped hole is 1.5 mm further along y: its row moves 1.5 mm, the spacing
    reads 12 +- 1.5 mm, the other holes stay. Without the change: there is no row or spacing to move."""
    node = asm.printed()["heat_sink"]
    base = ET.fromstring(drawing(asm, node).svg)
    holes = list(node.spec.holes)
    k = next(i for i, h in enumerate(holes) if h.diameter > 2.0)        # an M3 tap drill (the M1.6 are 1.25)
    h = holes[k]
    holes[k] = dataclasses.replace(h, origin=(h.origin[0], h.origin[1] + 1.5, h.origin[2]))
    moved = ET.fromstring(drawing(asm, _heat_sink_with(asm, tuple(holes))).svg)
    before, after = _rows(base), _rows(moved)
    shifted = [(p, q) for p, q in zip(before, after) if p["at"] != q["at"]]
    assert len(before) == len(after) and len(shifted) == 1
    (p, q), = shifted
    assert q["view"] == "plan" and q["at"][1] - p["at"][1] == pytest.approx(1.5, abs=1e-6)
    spacing, _ = _model_spacing(asm)
    got = float(_spacing(moved).get("data-value"))
    assert got == pytest.approx(spacing + 1.5, abs=1e-6) or got == pytest.approx(spacing - 1.5, abs=1e-6)


def test_positions_come_from_the_solid(asm):
    """A heat sink whose solid has a hole 1 mm away from where its spec says: the row at the spec's place
    says the solid does not have it, and the solid's own hole is listed where it really is. Without the
    change: no rows at all (and a table read from the spec alone could not tell)."""
    node = asm.printed()["heat_sink"]
    holes = list(node.spec.holes)
    k = next(i for i, h in enumerate(holes) if h.diameter > 2.0)
    h = holes[k]
    cut = list(holes)
    cut[k] = dataclasses.replace(h, origin=(h.origin[0] + 1.0, h.origin[1], h.origin[2]))

    base = type(node.spec)

    class Liar(base):                            # lists the layout's holes, cuts one of them 1 mm off
        def build(self):
            return base.build(dataclasses.replace(self, holes=tuple(cut)))

    liar = dataclasses.replace(node, spec=Liar(**{f.name: getattr(node.spec, f.name)
                                                  for f in dataclasses.fields(node.spec)}), _shape=None)
    rows = _rows(ET.fromstring(drawing(asm, liar).svg))
    lost = [r for r in rows if not r["on_solid"]]
    assert len(lost) == 1 and "not on the solid" in lost[0]["text"]
    good = {r["id"]: r for r in _rows(ET.fromstring(drawing(asm, node).svg))}
    ref = next(r for r in good.values() if r["d"] == pytest.approx(h.diameter) and r["at"] == pytest.approx(lost[0]["at"]))
    found = [r for r in rows if r["on_solid"] and r["d"] == pytest.approx(h.diameter)
             and r["at"] == pytest.approx((ref["at"][0] + 1.0, ref["at"][1]), abs=1e-6)]
    assert len(found) == 1 and found[0]["purpose"] == "hole"


def test_a_set_override_moves_the_handle_holes(asm):
    """``--set enclosure.handles.grip_length_mm=...`` (the same loader the CLI's --set uses): the handle's
    outer foot screws move apart by the change in length, on the drawing. Without the change: no rows."""
    from platform_tools.rig import load_rig
    from cad.assembly import build
    g0 = asm.rig.desc.enclosure.handles.grip_length_mm
    longer = build(load_rig(overrides=[f"enclosure.handles.grip_length_mm={g0 + 10:g}"]))

    def span(a) -> float:
        xs = [r["at"][0] for r in _rows(ET.fromstring(drawing(a, a.printed()["handle"]).svg))
              if r["purpose"] == "clearance M3"]
        assert len(xs) == 4
        return max(xs) - min(xs)

    def model_span(a) -> float:
        xs = a.layout.handles.geometry.foot_screw_x()
        return max(xs) - min(xs)

    assert span(asm) == pytest.approx(model_span(asm), abs=0.01)
    assert span(longer) == pytest.approx(model_span(longer), abs=0.01)
    assert span(longer) - span(asm) == pytest.approx(model_span(longer) - model_span(asm), abs=0.01) != 0
