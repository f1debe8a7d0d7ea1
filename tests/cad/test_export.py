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
        assert b'class="dim"' in (exported / "printed" / f"{pid}.drawing.svg").read_bytes()   # its drawing beside it
        shape = cq.importers.importStep(str(step)).val()
        bb = shape.BoundingBox()
        # OCC's box of a re-read STEP turned off its axes is up to ~0.01 mm loose: take its mesh's lowest point
        verts, _ = shape.tessellate(0.01, 0.1)
        assert min(v.z for v in verts) == pytest.approx(0.0, abs=1e-3)
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
def test_an_impossible_design_is_bad_input_in_every_command(tmp_path):
    """One line per rig key with its real limit, exit 2, no traceback, in check, params and export."""
    report = tmp_path / "report.txt"
    out = tmp_path / "out"
    for args in (("check", "--report", str(report)), ("params",), ("export", "SVG", "--out", str(out))):
        r = run(*args, "--set", "enclosure.handles.grip_length_mm=160")
        assert r.returncode == 2, (args, r.stderr)
        lines = r.stderr.strip().splitlines()
        assert len(lines) == 1 and "Traceback" not in r.stderr, r.stderr
        assert "enclosure.handles.grip_length_mm: got 160 mm" in lines[0] and "expected 64.0 to 150.4 mm" in lines[0]
    assert not report.exists() and not out.exists()


@pytest.mark.slow
def test_suggested_grip_limits_really_pass_and_fail():
    """The range the message suggests is the real one: its ends pass, 0.1 mm beyond them fails."""
    from platform_tools.rig import load_rig
    from cad.layout import design_problems
    def problems(length):
        return design_problems(load_rig(overrides=[f"enclosure.handles.grip_length_mm={length}"]))
    assert problems(64.0) == [] and problems(150.4) == []
    for bad in (63.9, 150.5, 300):
        [p] = problems(bad)
        assert p.key == "enclosure.handles.grip_length_mm" and "expected 64.0 to 150.4 mm" in p.message


@pytest.mark.slow
def test_export_refuses_a_folder_it_did_not_write(tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("someone's notes")
    r = run("export", "SVG", "--out", str(out))
    assert r.returncode == 2 and "not a previous export" in r.stderr and "notes.txt" in r.stderr
    assert (out / "notes.txt").read_text() == "someone's notes" and sorted(out.iterdir()) == [out / "notes.txt"]
    # a previous export (it holds the marker) is replaced whole
    fresh = tmp_path / "fresh"
    assert run("export", "SVG", "--out", str(fresh)).returncode == 0
    assert (fresh / ".rig-cad-export").is_file()
    (fresh / "views" / "stale.svg").write_text("<svg/>")
    assert run("export", "SVG", "--out", str(fresh)).returncode == 0
    assert not (fresh / "views" / "stale.svg").exists() and (fresh / "views" / "iso.svg").is_file()


@pytest.mark.slow
def test_params_json_has_resolved_values():
    import json
    r = run("params", "--json", "--set", "enclosure.wall_mm=3")
    assert r.returncode == 0, r.stderr
    doc = json.loads(r.stdout)
    assert doc["rig"]["enclosure"]["wall_mm"] == 3
    assert doc["derived"]["case_outer_mm"]["size"][1] > 170
