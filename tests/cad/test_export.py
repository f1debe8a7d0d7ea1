"""Exports are real files; the STEP round-trips with names, colours and volumes."""
import subprocess
import sys
from pathlib import Path

import cadquery as cq
import pytest

from cad.export import export
from platform_tools.rig.atomic import OutputDir

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def exported(asm, tmp_path_factory):
    out = tmp_path_factory.mktemp("cad") / "out"
    with OutputDir(out) as stage:
        export(asm, stage, {"STEP", "STL", "GLB", "SVG", "PNG"})
    return out


@pytest.mark.slow
def test_step_round_trip(asm, exported):
    imported = cq.Assembly.importStep(str(exported / "rig_assembly.step"))
    got = {name: sub for name, sub in imported.traverse() if sub.obj is not None}
    assert set(got) == {n.name for n in asm.nodes}
    for n in asm.nodes:
        sub = got[n.name]
        assert sub.color is not None
        assert sub.color.toTuple() == pytest.approx(n.colour, abs=1e-3), n.name
        assert sub.obj.Volume() == pytest.approx(n.local_shape(asm.cache).Volume(), rel=1e-4), n.name


@pytest.mark.slow
def test_printed_parts_exported_on_the_bed(asm, exported):
    bed = asm.rig.desc.printing.printer.bed_mm
    for pid, n in asm.printed().items():
        if n.category != "printed":
            continue
        step = exported / "printed" / f"{pid}.step"
        stl = exported / "printed" / f"{pid}.stl"
        assert step.read_bytes()[:13] == b"ISO-10303-21;" and stl.stat().st_size > 84
        shape = cq.importers.importStep(str(step)).val()
        bb = shape.BoundingBox()
        assert bb.zmin == pytest.approx(0.0, abs=1e-3)
        assert bb.xlen <= bed[0] and bb.ylen <= bed[1] and bb.zlen <= bed[2]


def test_views_are_pictures(exported):
    for view in ("iso", "front", "top", "exploded"):
        assert (exported / "views" / f"{view}.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert b"<svg" in (exported / "views" / f"{view}.svg").read_bytes()[:500]
    assert (exported / "rig_assembly.glb").read_bytes()[:4] == b"glTF"


def run(*args, cwd=REPO):
    return subprocess.run([sys.executable, "cad/build.py", *args], cwd=cwd, capture_output=True, text=True)


@pytest.mark.slow
def test_bad_input_is_one_line_and_leaves_nothing(tmp_path):
    out = tmp_path / "out"
    for args, needle in [(("export", "DXF", "--out", str(out)), "unknown export format"),
                         (("export", "STEP", "--out", str(out), "--set", "enclosure.wal_mm=3"), "enclosure.wall_mm"),
                         (("export", "STEP", "--out", str(out), "--set", "sensors.thermal.pose.xyz_mm=[0,0,-30]"),
                          "sensors.thermal.pose.xyz_mm")]:
        r = run(*args)
        assert r.returncode == 2, r.stderr
        assert needle in r.stderr and "Traceback" not in r.stderr
    assert not out.exists() and list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_unwritable_output_folder(tmp_path):
    target = tmp_path / "file"
    target.write_text("x")
    r = run("export", "SVG", "--out", str(target / "sub"))
    assert r.returncode == 2 and "Traceback" not in r.stderr and str(target) in r.stderr


@pytest.mark.slow
def test_check_fails_with_the_constraint_named(tmp_path):
    report = tmp_path / "report.txt"
    r = run("check", "--set", "sensors.thermal.baseline_mm=40", "--report", str(report))
    assert r.returncode == 1
    assert "sensors.thermal.baseline_mm" in report.read_text() and "Traceback" not in r.stderr


@pytest.mark.slow
def test_params_json_has_resolved_values():
    import json
    r = run("params", "--json", "--set", "enclosure.wall_mm=3")
    assert r.returncode == 0, r.stderr
    doc = json.loads(r.stdout)
    assert doc["rig"]["enclosure"]["wall_mm"] == 3
    assert doc["derived"]["case_outer_mm"]["size"][1] > 170
