"""The layout and placement follow the rig description."""
import numpy as np
import pytest
from OCP.BRepClass3d import BRepClass3d_SolidClassifier
from OCP.gp import gp_Pnt
from OCP.TopAbs import TopAbs_IN

from cad.assembly import build, camera_frames
from cad.layout import design_problems, layout
from cad.solids import bounds_of
from platform_tools.rig import load_rig


def inside(shape, p) -> bool:
    c = BRepClass3d_SolidClassifier(shape.wrapped, gp_Pnt(*p), 1e-6)
    return c.State() == TopAbs_IN


def test_camera_frames_are_the_rigs(rig, asm):
    frames = camera_frames(asm)
    assert set(frames) == {"zed_x_left_optical", "zed_x_right_optical", "thermal_left_optical", "thermal_right_optical"}
    for name, T in frames.items():
        assert T.isclose(rig.frame(name), mm=1e-9, deg=1e-9), name


def test_case_holds_every_internal_part(asm):
    inner = asm.layout.case.interior
    for name in ("jetson_agx_orin", "zed_link_quad", "heat_sink_left", "fan_right", "dc_converter", "thermal_mount"):
        b = bounds_of(asm.node(name).shape(asm.cache))
        assert all(lo >= ilo - 1e-6 for lo, ilo in zip(b.lo, inner.lo)), name
        assert all(hi <= ihi + 1e-6 for hi, ihi in zip(b.hi, inner.hi)), name


def test_zed_front_is_flush_with_the_case_and_split_is_under_it(asm):
    lay = asm.layout
    zb = bounds_of(asm.node("zed_x").shape(asm.cache))
    assert zb.hi[0] == pytest.approx(lay.case.outer.hi[0], abs=1e-6)
    assert lay.case.split_z == pytest.approx(zb.lo[2] - lay.fits.clear)
    lower = bounds_of(asm.node("case_lower").shape(asm.cache))
    lid = bounds_of(asm.node("case_lid").shape(asm.cache))
    assert lower.hi[2] == pytest.approx(lay.case.split_z, abs=1e-6)
    assert lid.lo[2] == pytest.approx(lay.case.split_z, abs=1e-6)


def test_heat_sink_volume_matches_its_drawing(rig, asm):
    hs = rig.desc.enclosure.heat_sink
    x, y, z = (rig.part("boson_640").envelope_mm.x.value, rig.part("boson_640").envelope_mm.y.value,
               rig.part("boson_640").envelope_mm.z.value)
    w, base = hs.wall_mm, asm.layout.c.heat_sink_base_mm
    sleeve = ((y + 2 * w) * (z + 2 * w) - y * z) * x
    fins = 2 * hs.fin_count * hs.fin_thickness_mm * hs.fin_height_mm * x
    block = (y + 2 * w) * base * x
    holes = sum(np.pi / 4 * h.diameter ** 2 * min(h.depth, base) for h in asm.node("heat_sink_left").spec.holes)
    # the front stop ring: the sleeve and block's section, stop_mm thick, bored for the lens
    bore = asm.layout.cameras.lens.diameter_mm + 2 * rig.desc.printing.fits.sliding_mm
    ring = ((y + 2 * w) * (z + 2 * w + base) - np.pi / 4 * bore ** 2) * hs.stop_mm
    vol = asm.node("heat_sink_left").local_shape(asm.cache).Volume()
    assert vol == pytest.approx(sleeve + fins + block + ring - holes, rel=0.01)


@pytest.mark.slow
def test_moving_the_thermal_pair_moves_its_mount_window_and_frame(rig, asm):
    moved_rig = load_rig(overrides=["sensors.thermal.pose.xyz_mm=[0,0,-52]"])
    asm2 = build(moved_rig)
    dz = -6.0
    for name in ("boson_left", "heat_sink_right", "fan_left"):
        a, b = asm.node(name).pose.t, asm2.node(name).pose.t
        assert b - a == pytest.approx([0, 0, dz], abs=1e-9), name
    bar1, bar2 = bounds_of(asm.node("thermal_mount").shape(asm.cache)), bounds_of(asm2.node("thermal_mount").shape(asm2.cache))
    assert bar2.hi[2] - bar1.hi[2] == pytest.approx(dz)
    assert camera_frames(asm2)["thermal_left_optical"].t[2] == pytest.approx(-52.0)
    # the window in the front wall follows the camera: open on the new axis, solid where the old edge was
    lay2 = asm2.layout
    x_wall = lay2.case.outer.hi[0] - lay2.fits.wall / 2
    y = rig.desc.sensors.thermal.baseline_mm / 2
    lower2 = asm2.node("case_lower").shape(asm2.cache)
    assert not inside(lower2, (x_wall, y, -52.0))
    lower1 = asm.node("case_lower").shape(asm.cache)
    assert not inside(lower1, (x_wall, y, -46.0))


@pytest.mark.slow
@pytest.mark.parametrize("override, key", [
    ("sensors.thermal.pose.xyz_mm=[0,0,-30]", "sensors.thermal.pose.xyz_mm"),
    ("sensors.thermal.baseline_mm=40", "sensors.thermal.baseline_mm"),
    ("enclosure.handles.grip_length_mm=200", "enclosure.handles.grip_length_mm"),
    ("parts.zed_x.dims.baseline_mm.value=160", "parts.zed_x.dims.baseline_mm"),
])
def test_impossible_values_name_the_constraint(override, key):
    problems = design_problems(load_rig(overrides=[override]))
    assert problems, override
    assert any(p.key == key for p in problems), [str(p) for p in problems]


def test_default_design_has_no_problems(rig):
    assert design_problems(rig) == []
    assert len(layout(rig).joints) > 20


def test_the_layout_lists_the_boson_clamp_screws_as_the_assembly_places_them(rig, asm):
    """``layout()`` is what ``params`` prints: its joints are the assembly's, the retaining plates' M1.6 screws
    among them (one core screw and two anchors per Boson)."""
    lay = layout(rig)
    clamp = sorted(j.name for j in lay.joints if j.name.startswith("boson_clamp_"))
    assert clamp == sorted(f"boson_clamp_{s}_{k}" for s in ("left", "right") for k in ("core", "anchor_0", "anchor_1"))
    assert all(j.thread == "M1.6" for j in lay.joints if j.name in clamp)
    assert [j.name for j in lay.joints] == [j.name for j in asm.layout.joints]


def test_the_rear_wall_stands_the_deepest_rear_plug_behind_the_devkit(rig, monkeypatch):
    """The room between the devkit's port face and the rear wall's inner face is the deepest right-angle plug of
    the cable table plus the clearance; a deeper plug moves the wall back with it, nothing inside."""
    import dataclasses
    from cad.bought.cables import cable_table
    from cad.layout import build_layout, C
    lay = layout(rig)
    plugs = cable_table().plugs
    room = lay.compute.orin_box.lo[0] - lay.case.interior.lo[0]
    assert room == pytest.approx(max(p.depth_mm for p in plugs.values()) + lay.fits.clear)
    deeper = dataclasses.replace(cable_table(), plugs={**plugs, "deep": dataclasses.replace(
        next(iter(plugs.values())), depth_mm=20.0)})
    monkeypatch.setattr("cad.layout.case.cable_table", lambda: deeper)
    moved = build_layout(rig, C)
    assert moved.compute.orin_box.lo[0] - moved.case.interior.lo[0] == pytest.approx(20.0 + lay.fits.clear)
    assert moved.compute.orin_box == lay.compute.orin_box and moved.power.converter_box == lay.power.converter_box


def test_the_layout_and_its_limits_are_computed_without_cadquery(repo):
    """The layout, its design problems, the datums and the export folder's rules are numbers: a fresh process that
    makes them (what ``params`` and every refused ``--set`` do) loads neither CadQuery nor OpenCascade, and the
    parts' shapes still build once something asks for them."""
    import subprocess
    import sys
    code = ("import sys\n"
            "from platform_tools.rig import load_rig\n"
            "from cad.layout import design_problems, layout\n"
            "from cad.datums import camera_locations\n"
            "from cad.export_folder import FORMATS, foreign_files\n"
            "rig = load_rig()\n"
            "lay = layout(rig)\n"
            "assert camera_locations(lay) and not design_problems(rig)\n"
            "print(sorted(m for m in ('cadquery', 'OCP') if m in sys.modules))\n"
            "print(lay.joints[0].screw.build().isValid())\n"
            "print('cadquery' in sys.modules)\n")
    r = subprocess.run([sys.executable, "-c", code], cwd=repo, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == ["[]", "True", "True"], r.stdout
