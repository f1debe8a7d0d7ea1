"""The overhang and bridge check, on real STL files: deliberate defects fail it, printable shapes pass,
and the figures agree with another library's reading of the same files (trimesh)."""
import math

import cadquery as cq
import numpy as np
import pytest

from cad.printability import StlError, analyse, read_stl

MAX_DEG, MAX_BRIDGE = 45.0, 30.0


def stl_of(shape, tmp_path, name="part"):
    path = tmp_path / f"{name}.stl"
    cq.exporters.export(shape, str(path), "STL", tolerance=0.05, angularTolerance=0.1)
    return path


def box(x, y, z, at=(0, 0, 0)):
    return cq.Workplane().box(x, y, z, centered=False).translate(at).val()


def bridge(span, height=10.0, depth=10.0, leg=5.0):
    """Two legs ``span`` apart under a 3 mm deck: a bridge of ``span``."""
    legs = box(leg, depth, height).fuse(box(leg, depth, height, (leg + span, 0, 0)))
    return legs.fuse(box(span + 2 * leg, depth, 3, (0, 0, height))).clean()


def test_a_plain_block_needs_no_support(tmp_path):
    r = analyse(read_stl(stl_of(box(40, 30, 20), tmp_path)), MAX_DEG, MAX_BRIDGE)
    assert r.ok and r.regions == ()
    assert r.bed_contact_mm2 == pytest.approx(1200, rel=1e-6)


def test_a_short_bridge_passes_and_a_long_one_fails(tmp_path):
    short = analyse(read_stl(stl_of(bridge(20), tmp_path, "short")), MAX_DEG, MAX_BRIDGE)
    long = analyse(read_stl(stl_of(bridge(40), tmp_path, "long")), MAX_DEG, MAX_BRIDGE)
    assert short.ok
    [deck] = [g for g in short.regions if g.area_mm2 > 1]
    assert deck.span_mm == pytest.approx(20, abs=1.0)         # between the two legs
    assert deck.area_mm2 == pytest.approx(200, rel=1e-6)
    assert not long.ok
    [bad] = long.failing
    assert bad.span_mm == pytest.approx(40, abs=1.0) and bad.z_mm[0] == pytest.approx(10)


def test_a_ledge_and_a_floating_roof_fail(tmp_path):
    # a 20 mm ledge from a wall: supported on one edge only, so it bridges twice its reach
    ledge = box(10, 20, 30).fuse(box(20, 20, 3, (10, 0, 27))).clean()
    r = analyse(read_stl(stl_of(ledge, tmp_path, "ledge")), MAX_DEG, MAX_BRIDGE)
    assert not r.ok and r.failing[0].span_mm == pytest.approx(40, abs=1.0)
    # the case_lid defect: a plate held off the bed by pads under its middle, its edges free
    lid = box(100, 100, 3, (0, 0, 5)).fuse(box(10, 10, 5, (45, 45, 0))).clean()
    r = analyse(read_stl(stl_of(lid, tmp_path, "lid")), MAX_DEG, MAX_BRIDGE)
    assert not r.ok and r.failing[0].area_mm2 == pytest.approx(100 * 100 - 10 * 10, rel=1e-6)
    # a plate hanging in the air off a post's side: no supported edge at all
    flag = box(5, 5, 30).fuse(box(30, 5, 3, (5, 0, 20))).clean()
    r = analyse(read_stl(stl_of(flag, tmp_path, "flag")), MAX_DEG, MAX_BRIDGE)
    assert not r.ok


def test_45_degree_chamfers_pass_and_steeper_ones_fail(tmp_path):
    def wedge(angle_deg):
        """A wall leaning out over the bed at ``angle_deg`` from the vertical, 20 mm tall."""
        run = 20 * math.tan(math.radians(angle_deg))
        pts = [(0, 0), (10, 0), (10 + run, 20), (0, 20)]
        return cq.Workplane("XZ").polyline(pts).close().extrude(-10).val()
    ok = analyse(read_stl(stl_of(wedge(45), tmp_path, "w45")), MAX_DEG, MAX_BRIDGE)
    steep = analyse(read_stl(stl_of(wedge(60), tmp_path, "w60")), MAX_DEG, MAX_BRIDGE)
    assert ok.ok and ok.overhang_mm2 == 0
    assert not steep.ok and steep.overhang_mm2 == pytest.approx(10 * 20 / math.cos(math.radians(60)), rel=1e-6)


def test_a_teardrop_hole_passes_where_a_big_round_one_fails(tmp_path):
    r0 = 25.0
    wall = box(60, 10, 80)
    round_hole = wall.cut(cq.Workplane("XZ").center(30, 35).circle(r0).extrude(-10).val())
    r = analyse(read_stl(stl_of(round_hole, tmp_path, "round")), MAX_DEG, MAX_BRIDGE)
    assert not r.ok                                           # its crown is ~35 mm across at 45 deg
    k = r0 / math.sqrt(2)
    point = cq.Workplane("XZ").polyline([(30 - k, 35 + k), (30, 35 + r0 * math.sqrt(2)), (30 + k, 35 + k),
                                         (30, 35)]).close().extrude(-10).val()
    tear = round_hole.cut(point)
    t = analyse(read_stl(stl_of(tear, tmp_path, "tear")), MAX_DEG, MAX_BRIDGE)
    assert t.ok, [g.describe() for g in t.failing]


def test_bad_stl_is_named(tmp_path):
    p = tmp_path / "bad.stl"
    p.write_bytes(b"\x00" * 90)
    with pytest.raises(StlError, match="bad.stl"):
        read_stl(p)


@pytest.mark.slow
def test_every_printed_part_prints_without_support(asm, results):
    r = results["printable without supports"]
    assert r.ok, "\n".join(r.details)
    assert set(r.data) >= {"case_lid", "case_lower", "zed_mount", "fan_mount_left", "handle"}


@pytest.mark.slow
def test_figures_agree_with_trimesh_on_the_exported_stls(asm, tmp_path):
    """Another reader and another overhang sum on the same files: bed contact and overhang area."""
    trimesh = pytest.importorskip("trimesh")
    from cad.checks import printed_meshes
    from cad.printability import analyse as ours
    import cad.checks as checks
    meshes = printed_meshes(asm)
    limit = math.sin(math.radians(MAX_DEG + 1.0))
    for pid, tri in meshes.items():
        path = tmp_path / f"{pid}.stl"
        # write our triangles with numpy-stl-free plain code, read them with trimesh
        m = trimesh.Trimesh(vertices=tri.reshape(-1, 3), faces=np.arange(len(tri) * 3).reshape(-1, 3), process=False)
        m.export(path)
        tm = trimesh.load(path, process=False)
        z0 = tm.bounds[0][2]
        on_bed = (tm.triangles[:, :, 2] <= z0 + 0.05).all(axis=1)
        over = (-tm.face_normals[:, 2] > limit) & ~on_bed
        bed = on_bed & (tm.face_normals[:, 2] < -0.99)
        r = ours(read_stl(path), MAX_DEG, MAX_BRIDGE)
        assert r.overhang_mm2 == pytest.approx(tm.area_faces[over].sum(), rel=1e-4, abs=1e-3), pid
        assert r.bed_contact_mm2 == pytest.approx(tm.area_faces[bed].sum(), rel=1e-4), pid
        assert r.bed_contact_mm2 > 40, pid                     # every part stands on something
    assert checks.check_printable(asm, meshes).ok


@pytest.mark.slow
def test_the_old_lid_orientation_fails(asm):
    """The orientation the issue reported (upside down on the roof) fails with its floating roof."""
    from cad.checks import check_printable
    from cad.parts.common import PrintSetup
    import cad.checks as checks
    saved = checks.PRINT_SETUPS["case_lid"]
    try:
        checks.PRINT_SETUPS["case_lid"] = PrintSetup((180.0, 0.0, 0.0), "upside down")
        r = check_printable(asm)
    finally:
        checks.PRINT_SETUPS["case_lid"] = saved
    assert not r.ok
    # on the bed: the top handle's pads, less their insert holes (the issue measured 3,120 mm^2 with the
    # old 12 mm foot flanges; with 8 mm flanges the pads are shorter)
    lay = asm.layout
    top = [p for p in lay.handles.pads if p.hi[2] > lay.case.outer.hi[2]]
    holes = len(lay.handles.geometry.foot_screw_x()) * math.pi / 4 * lay.fits.insert.hole_diameter_mm ** 2
    pads = sum(p.size[0] * p.size[1] for p in top) - holes
    assert r.data["case_lid"]["failing"] and r.data["case_lid"]["bed_contact_mm2"] == pytest.approx(pads, rel=0.02)
