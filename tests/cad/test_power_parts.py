"""The power and sync parts as placed parts (issue 16, items 1 and 2): the cable gland in its hole in the
floor, the under-voltage cut-off on its bosses, a sync breakout on each Boson, each in the assembly,
the BOM's count and the guide's steps; the check that fails a blocked locknut or plug."""
from __future__ import annotations

import numpy as np
import pytest

from cad import checks
from cad.assembly_order import load_steps
from cad.electrical import electrical_checks, gland_check
from cad.geom import Bounds
from cad.solids import box, moved
from platform_tools.rig.loader import load_rig

pytestmark = pytest.mark.slow


def test_parts_are_placed_counted_and_in_the_guide(asm, rig):
    from cad.assembly import assembly_tree
    counts = assembly_tree(asm, volumes=False)["counts"]
    assert counts["cable_gland"] == 1 and counts["undervoltage_cutoff"] == 1
    assert counts["boson_sync_breakout"] == counts["boson_640"] == 2
    steps = {n: s.id for s in load_steps([n.name for n in asm.nodes]) for n in s.nodes}
    # the gland goes into the empty tray (its locknut's socket needs the room); the cut-off in the power step
    assert steps["cable_gland"] == "tray"
    assert steps["undervoltage_cutoff"] == steps["screw_cutoff_0"] == steps["insert_cutoff_1"] == "power"
    assert steps["sync_breakout_left"] == steps["boson_left"]


def test_check_passes_and_measures_the_table_hole(results, rig):
    r = results["power and sync parts"]
    assert r.ok, r.details
    assert r.data["gland_hole_mm"] == pytest.approx(rig.dim("cable_gland", "hole_diameter_mm"), abs=0.01)


def test_gland_hole_read_back_from_the_exported_stl(asm, rig, tmp_path):
    """Independent of the check's B-rep distance: trimesh sections the tray's STL mid-floor and the loop
    around the gland's axis is the table's hole."""
    import cadquery as cq
    import trimesh
    path = tmp_path / "case_lower.stl"
    cq.exporters.export(asm.node("case_lower").shape(asm.cache), str(path), "STL", tolerance=0.01, angularTolerance=0.05)
    mesh = trimesh.load(str(path))
    x, y, z = asm.layout.power.gland_pose.t
    sec = mesh.section(plane_origin=(0, 0, z + asm.layout.fits.wall / 2), plane_normal=(0, 0, 1))
    pts = np.asarray(sec.vertices)[:, :2]
    r = np.hypot(pts[:, 0] - x, pts[:, 1] - y)
    loop = r[r < 10.0]
    assert len(loop) > 20
    d = rig.dim("cable_gland", "hole_diameter_mm")
    assert loop.max() == pytest.approx(d / 2, abs=0.02) and loop.min() == pytest.approx(d / 2, abs=0.02)
    # nothing else of the tray cuts the floor near it: the next material edge is beyond the locknut's circle
    nut = rig.dim("cable_gland", "locknut_across_corners_mm")
    assert not np.any((r > d / 2 + 0.05) & (r < nut / 2))


def test_cutoff_stands_on_its_bosses(asm):
    """The tray has solid bosses under the cut-off's two holes, with an insert hole in each."""
    p, floor = asm.layout.power, asm.layout.case.interior.lo[2]
    tray = asm.node("case_lower").shape(asm.cache)
    ins = asm.layout.fits.insert
    for x, y, d, h in p.cutoff_seats:
        ring = (x + (ins.hole_diameter_mm + d) / 4, y, floor + h / 2)     # between the insert hole and the boss's edge
        assert tray.isInside(cq_vec(ring))
        assert not tray.isInside(cq_vec((x, y, floor + h - 1.0)))          # the insert's hole
    assert p.cutoff_pose.t[2] == pytest.approx(floor + max(b[3] for b in p.cutoff_seats))


def test_fuse_holder_stands_on_its_bosses(asm, rig, tmp_path):
    """The fuse holder's tabs lie on two bosses of the tray, one under each tab hole, with an insert hole in
    each: measured on the placed solids (the holder touches the tray and does not cut into it), on the tray's
    exported STL (trimesh: a boss ring around an insert hole of the insert's table diameter under each tab
    hole) and in the joints (a screw down through each tab into an insert of the boss)."""
    from OCP.BRepExtrema import BRepExtrema_DistShapeShape
    from cad.solids import common_volume_mm3
    lay = asm.layout
    p, floor, ins = lay.power, lay.case.interior.lo[2], lay.fits.insert
    fuse, tray = asm.node("blade_fuse").shape(asm.cache), asm.node("case_lower").shape(asm.cache)
    d = BRepExtrema_DistShapeShape(fuse.wrapped, tray.wrapped)
    d.Perform()
    assert d.Value() < 1e-6                                      # in contact: no gap under the tabs ...
    assert common_volume_mm3(fuse, tray) < 1e-3                  # ... and not sunk into the tray
    holes = [tuple(p.fuse_pose.apply(np.array(pt))) for pt in p.fuse.mount_points()]
    assert len(holes) == len(p.fuse_bosses) == 2
    assert fuse.BoundingBox().zmin == pytest.approx(floor + lay.fits.insert_plate_mm, abs=1e-6)
    mesh = _stl_mesh(asm, "case_lower", tmp_path)
    for (hx, hy, hz), (bx, by, bd, bh) in zip(holes, p.fuse_bosses):
        assert (bx, by) == pytest.approx((hx, hy)) and hz == pytest.approx(floor + bh)
        assert bh >= ins.hole_depth_mm and bd > ins.outer_diameter_mm    # the boss holds the insert
        loop = _loop_around(mesh, (0, 0, floor + bh / 2), (0, 0, 1), (hx, hy), ((1, 0, 0), (0, 1, 0)))
        r = np.hypot(loop[:, 0] - hx, loop[:, 1] - hy)
        assert r.max() == pytest.approx(ins.hole_diameter_mm / 2, abs=0.05) and r.min() > ins.hole_diameter_mm / 2 - 0.05
        assert _inside(mesh, [(hx + (ins.hole_diameter_mm + bd) / 4, hy, floor + bh / 2)]).all()   # the boss's ring
    screws = [j for j in lay.joints if j.name.startswith("fuse_")]
    assert len(screws) == 2 and all(j.kind == "insert" and j.host == "case_lower" for j in screws)
    for j, (hx, hy, hz) in zip(screws, holes):
        assert j.head == pytest.approx((hx, hy, hz + p.fuse.tab_mm)) and j.grip_mm == p.fuse.tab_mm
        assert asm.node(f"insert_fuse_{screws.index(j)}") is not None


def test_a_fuse_holder_whose_tabs_take_another_screw_is_refused():
    """The rig's own mounting for the holder (once measured) replaces the estimate; one that names a thread
    the floor's inserts do not take is one line naming the key."""
    from cad.layout import DesignError, layout
    pattern = "[{face: bottom, thread: M2.5, positions_mm: [[-16, 0], [16, 0]], depth_mm: 2, source: estimate, confidence: estimate}]"
    rig = load_rig(overrides=[f"parts.blade_fuse.mounting={pattern}"])
    with pytest.raises(DesignError) as e:
        layout(rig)
    text = str(e.value)
    assert text.startswith("parts.blade_fuse.mounting: ") and "M2.5" in text and len(text.splitlines()) == 1, text


def cq_vec(p):
    import cadquery as cq
    return cq.Vector(*p)


def test_a_part_over_the_locknut_fails(asm):
    x, y, _ = asm.layout.power.gland_pose.t
    floor = asm.layout.case.interior.lo[2]
    block = box(Bounds((x - 3, y - 3, floor + 20), (x + 3, y + 3, floor + 25)))
    r = checks.check_power_parts(asm, extra=[("test_block", block)])
    assert not r.ok
    assert any("locknut cannot be tightened" in p and "test_block" in p for p in r.details), r.details


def test_the_floor_bosses_stand_clear_of_the_locknut_socket_in_the_tray_stl(asm, tmp_path):
    """The tray's own bosses beside the gland (the fuse holder's ahead of it, the cut-off's behind it) once stood
    1.65 and 0.18 mm inside the socket's path (the layout spaced them from the locknut, not from the socket round
    it; the check left case_lower out). Independent of the check's B-rep: trimesh sections the tray's STL 1 mm
    over the floor and no material lies within the socket's circle round the gland's axis."""
    from cad.layout.power import SOCKET_WALL_MM
    p = asm.layout.power
    x, y, _ = p.gland_pose.t
    floor = asm.layout.case.interior.lo[2]
    sock = p.gland.nut_d_mm / 2 + SOCKET_WALL_MM
    mesh = _stl_mesh(asm, "case_lower", tmp_path)
    sec = mesh.section(plane_origin=(0, 0, floor + 1.0), plane_normal=(0, 0, 1))
    pts = np.asarray(sec.vertices)[:, :2]
    r = np.hypot(pts[:, 0] - x, pts[:, 1] - y)
    # the bosses touch the socket's circle (the strip has no room for more: 1 mm more put the cut-off into the
    # left fan mount); the STL's chords lie inside the round boss, so a vertex is at most on that circle
    assert r.min() > sock - 0.01, f"tray material {r.min():.2f} mm from the gland's axis, inside the {sock:.2f} mm socket"
    assert r.min() < sock + 0.05        # the nearest thing there is a boss, where the layout spaces it


def test_a_boss_in_the_socket_path_fails_the_check(asm, monkeypatch):
    """The check reads the tray too: with a socket 1.5 mm fatter a side than the one the layout spaced the
    bosses for, the bosses (1 mm clear) are in its way and case_lower is named."""
    from cad import passthrough
    assert checks.check_power_parts(asm).ok
    monkeypatch.setattr(passthrough, "SOCKET_WALL_MM", passthrough.SOCKET_WALL_MM + 1.5)
    r = checks.check_power_parts(asm)
    assert not r.ok
    assert any("locknut cannot be tightened" in d and "case_lower" in d for d in r.details), r.details


def test_a_part_behind_a_breakout_fails(asm):
    pose = asm.layout.power.breakout_poses["left"]
    behind = moved(box(Bounds((-12, -2, -2), (-8, 2, 2))), pose)   # 3-7 mm behind the board's rear face
    r = checks.check_power_parts(asm, extra=[("test_block", behind)])
    assert not r.ok
    assert any(p.startswith("sync_breakout_left: no room to plug") and "test_block" in p for p in r.details), r.details
    assert not any(p.startswith("sync_breakout_right: no room") for p in r.details)


COUNTS = {"jetson_agx_orin": 1, "zed_x": 1, "boson_640": 2, "zed_link_quad": 1, "fan_3010_5v": 2}


@pytest.mark.parametrize("override, name", [
    ("parts.cable_gland.dims.cable_diameter_mm.value=8", "cable gland"),       # the seal cannot grip it
    ("parts.cable_gland.dims.hole_diameter_mm.value=12", "cable gland"),       # under the 12.5 mm thread
    ("parts.undervoltage_cutoff.rating_a.value=5", "cut-off rating"),          # under the 7.5 A fuse
    ("parts.undervoltage_cutoff.supply_v.min=16", "cut-off rating"),           # dead above the 15 V it must act at
])
def test_electrical_fails_a_bad_gland_or_cutoff(override, name):
    res = {r.name: r for r in electrical_checks(load_rig(overrides=[override]), COUNTS)}
    assert not res[name].ok, res[name].text
    assert all(r.ok for n, r in res.items() if n != name), [r.text for r in res.values() if not r.ok]


def test_default_gland_grips_the_lead():
    assert gland_check(load_rig()).ok


# ------------------------------------------------------------------ the real switch and the converter's screws
def _stl_mesh(asm, node: str, tmp_path):
    """A node's exported STL read back by trimesh: the geometry as a print service gets it."""
    import cadquery as cq
    import trimesh
    path = tmp_path / f"{node}.stl"
    cq.exporters.export(asm.node(node).shape(asm.cache), str(path), "STL", tolerance=0.01, angularTolerance=0.05)
    return trimesh.load(str(path))


def _loop_around(mesh, origin, normal, centre_uv, axes):
    """The smallest closed loop of the section of ``mesh`` by the plane through ``origin`` with ``normal``
    that encloses ``centre_uv``, in the plane's (u, v) coordinates along ``axes``: the hole there. The
    section's segments (trimesh.intersections.mesh_plane) are joined into loops by their shared ends."""
    import trimesh
    seg = trimesh.intersections.mesh_plane(mesh, np.asarray(normal, float), np.asarray(origin, float))
    assert len(seg), "the plane misses the part"
    uv = np.stack([seg @ np.asarray(axes[0], float), seg @ np.asarray(axes[1], float)], axis=-1)   # (n, 2, 2)
    keys = np.round(uv.reshape(-1, 2), 4)
    _, ids = np.unique(keys, axis=0, return_inverse=True)
    parent = list(range(ids.max() + 1))
    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i
    for a, b in ids.reshape(-1, 2):
        parent[find(a)] = find(b)
    roots = np.array([find(i) for i in ids.reshape(-1, 2)[:, 0]])
    best = None
    for r in set(roots.tolist()):
        pts = uv[roots == r].reshape(-1, 2)
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        if np.all(lo < centre_uv) and np.all(centre_uv < hi):
            area = float(np.prod(hi - lo))
            if best is None or area < best[0]:
                best = (area, pts)
    assert best is not None, f"no loop of the section encloses {centre_uv}"
    return best[1]


def _inside(mesh, pts, chunk=8):
    """Which ``pts`` lie inside the closed ``mesh``: its generalised winding number (the solid angle its
    triangles subtend, Van Oosterom and Strackee, over 4 pi) is 1 inside, 0 outside. No ray caster, no
    broad phase: every triangle counts."""
    tri = np.asarray(mesh.triangles, float)
    out = np.zeros(len(pts), bool)
    for k in range(0, len(pts), chunk):
        p = np.asarray(pts[k:k + chunk], float)[:, None, None, :]
        a, b, c = (tri[None, :, i, :] - p[:, :, 0, :] for i in range(3))
        la, lb, lc = (np.linalg.norm(v, axis=-1) for v in (a, b, c))
        num = np.einsum("ptk,ptk->pt", a, np.cross(b, c))
        den = la * lb * lc + np.einsum("ptk,ptk->pt", a, b) * lc + np.einsum("ptk,ptk->pt", b, c) * la \
            + np.einsum("ptk,ptk->pt", c, a) * lb
        w = 2 * np.arctan2(num, den).sum(axis=1) / (4 * np.pi)
        out[k:k + chunk] = np.abs(w) > 0.5
    return out


def test_switch_cutout_is_the_datasheets_hole(asm, rig, tmp_path):
    """The lid's hole for the Carling L-Series, sectioned mid-wall on the exported STL (trimesh, not the
    B-rep the CAD model cut it from): no smaller than the datasheet's 44.0 x 22.0 mm even if the printer
    shrinks it by its tolerance on each side, and no more than 1 mm larger (the snap-in's latches must bite)."""
    mesh = _stl_mesh(asm, "case_lid", tmp_path)
    _, pose = asm.layout.controls["power_switch"]
    o, wall = asm.layout.case.outer, asm.layout.fits.wall
    _, y, z = pose.t
    loop = _loop_around(mesh, (o.lo[0] + wall / 2, 0, 0), (1, 0, 0), (y, z), ((0, 1, 0), (0, 0, 1)))
    assert len(loop) >= 4
    width, height = np.ptp(loop[:, 0]), np.ptp(loop[:, 1])
    tol = rig.desc.printing.printer.tolerance_mm
    for got, want in ((width, rig.dim("power_switch", "cutout_width_mm")),
                      (height, rig.dim("power_switch", "cutout_height_mm"))):
        assert want + 2 * tol <= got <= want + 1.0, (got, want)
    # centred on the switch's pose: the body behind it is where the model says
    assert (loop[:, 0].min() + loop[:, 0].max()) / 2 == pytest.approx(y, abs=0.05)
    assert (loop[:, 1].min() + loop[:, 1].max()) / 2 == pytest.approx(z, abs=0.05)


def test_switch_is_clear_of_every_part(asm, tmp_path):
    """Points sampled inside the switch's exported mesh lie inside no other part's mesh (a winding-number
    inside test on the STL triangles, beside the interference check's B-rep common volumes): its body behind
    the lid's rear wall clears the devkit, the capture card and the antenna beside it, its neck passes the
    wall's hole."""
    sw = _stl_mesh(asm, "power_switch", tmp_path)
    assert sw.is_watertight
    lo, hi = sw.bounds
    g = np.stack(np.meshgrid(*[np.linspace(a + 0.2, b - 0.2, 10) for a, b in zip(lo, hi)]), -1).reshape(-1, 3)
    pts = g[_inside(sw, g)]
    assert len(pts) > 200
    checked = []
    for n in asm.nodes:
        if n.name == "power_switch" or n.category == "fastener":
            continue
        bb = n.shape(asm.cache).BoundingBox()
        if np.any(np.array([bb.xmax, bb.ymax, bb.zmax]) < lo) or np.any(np.array([bb.xmin, bb.ymin, bb.zmin]) > hi):
            continue
        other = _stl_mesh(asm, n.name, tmp_path)
        inside = _inside(other, pts)
        assert not inside.any(), f"{n.name} holds {int(inside.sum())} points of the switch"
        checked.append(n.name)
    assert "case_lid" in checked      # the wall it stands in was tested, not skipped


def test_a_switch_over_the_devkit_is_raised_clear_of_it(asm):
    """Its body reaches in over the devkit from the rear wall: it stands above the devkit's top by the
    clearance (placed, not by luck: at the lid's mid height it would cut into the devkit)."""
    lay = asm.layout
    sw, pose = lay.controls["power_switch"]
    from cad.geom import placed_bounds
    body, orin = placed_bounds(sw.body_bounds(), pose), lay.compute.orin_box
    assert body.lo[0] < orin.lo[0] < body.hi[0]                     # it does reach in over the devkit
    assert body.lo[1] < orin.lo[1] + 20                              # beside its edge, over its footprint
    assert body.lo[2] >= orin.hi[2] + lay.fits.clear - 1e-6
    mid = (lay.case.split_z + lay.case.interior.hi[2]) / 2
    assert mid - sw.size[2] / 2 < orin.hi[2]                         # the lid's mid height would not have cleared it


def test_converter_screws_cross_the_wall_at_its_mounting_holes(asm, rig, tmp_path):
    """The right wall of the exported tray, sectioned mid-wall (trimesh): a round hole at each of the
    converter's mounting positions (parts.dc_converter.mounting, through its pose), and the screws the joints
    drive through them."""
    p = asm.layout.power
    mesh = _stl_mesh(asm, "case_lower", tmp_path)
    wall = asm.layout.fits.wall
    y_mid = asm.layout.case.outer.lo[1] + wall / 2
    holes = p.converter.mount_points()
    assert holes
    for pt in holes:
        c = p.converter_pose.apply(np.array(pt))
        loop = _loop_around(mesh, (0, y_mid, 0), (0, 1, 0), (c[0], c[2]), ((1, 0, 0), (0, 0, 1)))
        assert len(loop) > 12, f"no hole at {c}"
        r = np.hypot(loop[:, 0] - c[0], loop[:, 1] - c[2])
        assert r.max() - r.min() < 0.1 and 1.0 < r.mean() < 2.5, (c, r.min(), r.max())   # a round M3 hole on it
    screws = [n for n in asm.nodes if n.name.startswith("screw_converter_")]
    assert len(screws) == len(holes)


def test_a_bezel_too_tall_for_the_lid_is_one_line_naming_its_key():
    """A switch whose bezel cannot stand in the lid's rear wall once raised over the devkit: the layout is
    refused with the rig key and the roof edge it runs into (exit 2 through the commands), not a clash."""
    from cad.layout import DesignError, layout
    rig = load_rig(overrides=["parts.power_switch.dims.bezel_height_mm.value=60"])
    with pytest.raises(DesignError) as e:
        layout(rig)
    text = str(e.value)
    assert "parts.power_switch.dims.bezel_height_mm: the 60 mm bezel" in text and "roof edge" in text, text
    assert len(text.splitlines()) == 1, text
    layout(load_rig(overrides=["parts.power_switch.dims.bezel_height_mm.value=30"]))   # a little taller still fits
