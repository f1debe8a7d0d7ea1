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
@pytest.mark.parametrize("value", ["-5", "0"])
def test_a_value_the_loader_refuses_gets_the_layouts_limit_in_every_command(tmp_path, value):
    """-5 and 0 are refused by the rig loader (a length is > 0); the message still gives the layout's real
    range, as 160 does: one line, exit 2, in check, params and export, nothing written."""
    report = tmp_path / "report.txt"
    out = tmp_path / "out"
    for args in (("check", "--report", str(report)), ("params",), ("export", "SVG", "--out", str(out))):
        r = run(*args, "--set", f"enclosure.handles.grip_length_mm={value}")
        assert r.returncode == 2, (args, r.stderr)
        lines = r.stderr.strip().splitlines()
        assert len(lines) == 1 and "Traceback" not in r.stderr, r.stderr
        assert f"enclosure.handles.grip_length_mm: got {value} mm" in lines[0], lines[0]
        assert "expected 64.0 to 150.4 mm" in lines[0] and "> 0" not in lines[0], lines[0]
    assert not report.exists() and not out.exists()


@pytest.mark.slow
def test_layout_limits_beside_the_loaders_other_problems():
    """Each refused --set keeps its own line; a layout-limited key gets the layout's limit, the real one
    (12.8 mm passes, 12.7 fails), others keep the loader's words; without handles no layout limit applies."""
    from platform_tools.rig import load_rig
    from cad.layout import design_problems
    r = run("params", "--set", "enclosure.handles.clearance_mm=-1", "--set", "enclosure.wall_mm=abc",
            "--set", "enclosure.handles.grip_length_mm=0")
    assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 3, r.stderr
    assert any("enclosure.handles.clearance_mm: got -1 mm; expected >= 12.8 mm" in x for x in lines), r.stderr
    assert any("enclosure.handles.grip_length_mm: got 0 mm; expected 64.0 to 150.4 mm" in x for x in lines), r.stderr
    assert any("enclosure.wall_mm: got 'abc'" in x for x in lines), r.stderr
    def problems(v):
        return design_problems(load_rig(overrides=[f"enclosure.handles.clearance_mm={v}"]))
    assert problems(12.8) == [] and [p.key for p in problems(12.7)] == ["enclosure.handles.clearance_mm"]
    r = run("params", "--set", "enclosure.handles.top=false", "--set", "enclosure.handles.sides=false",
            "--set", "enclosure.handles.grip_length_mm=-5")
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1 and "> 0" in r.stderr, r.stderr


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


@pytest.fixture(scope="module")
def previous_export(tmp_path_factory):
    """A real previous export through the CLI (SVG, the cheapest format): each test copies it."""
    out = tmp_path_factory.mktemp("previous") / "export"
    r = run("export", "SVG", "--out", str(out))
    assert r.returncode == 0, r.stderr
    return out


def _copy(previous, tmp_path):
    import shutil
    out = tmp_path / "out"
    shutil.copytree(previous, out)
    return out


def _state(folder):
    """Everything a replacement would change: the folder itself, every entry, its bytes and times."""
    return folder.stat().st_ino, {p.relative_to(folder).as_posix(): (p.read_bytes() if p.is_file() else None,
                                                                     p.stat().st_mtime_ns)
                                  for p in sorted(folder.rglob("*"))}


def _refused(out, needle):
    before = _state(out)
    r = run("export", "SVG", "--out", str(out))
    assert r.returncode == 2, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in r.stderr, r.stderr
    assert str(out) in lines[0] and needle in lines[0] and "did not write" in lines[0], lines[0]
    assert _state(out) == before                        # not swapped, not one byte or time changed
    assert list(out.parent.iterdir()) == [out]          # no staging folder left beside it


@pytest.mark.slow
def test_a_previous_export_holding_a_user_file_is_refused(previous_export, tmp_path):
    """--out never deletes what it did not write: a user's file in a previous export stops the export."""
    out = _copy(previous_export, tmp_path)
    (out / "notes.txt").write_bytes(b"my measurements\n\x00\xff")
    _refused(out, "notes.txt")
    assert (out / "notes.txt").read_bytes() == b"my measurements\n\x00\xff"


@pytest.mark.slow
def test_a_previous_export_holding_a_user_folder_is_refused(previous_export, tmp_path):
    out = _copy(previous_export, tmp_path)
    (out / "scans").mkdir()
    (out / "scans" / "a.ply").write_text("ply")
    _refused(out, "scans/")
    (out / "scans" / "a.ply").unlink()
    _refused(out, "scans/")                              # an empty folder of the user's is the user's too
    (out / "scans").rmdir()
    (out / "views" / "mine").mkdir()                     # inside a folder the export writes
    _refused(out, "views/mine/")


@pytest.mark.slow
def test_a_user_file_named_like_an_export_file_is_refused(previous_export, tmp_path):
    """The previous export's manifest, not the export's file patterns, says what it wrote."""
    out = _copy(previous_export, tmp_path)
    (out / "views" / "my_sketch.svg").write_text("<svg/>")
    _refused(out, "views/my_sketch.svg")


@pytest.mark.slow
def test_a_previous_export_alone_is_replaced(previous_export, tmp_path):
    """What the previous export recorded (here also a view an earlier version wrote) is replaced whole;
    the new marker lists exactly the files the new export wrote."""
    import json
    out = _copy(previous_export, tmp_path)
    marker = out / ".rig-cad-export"
    doc = json.loads(marker.read_text())
    doc["files"].append("views/side.svg")
    marker.write_text(json.dumps(doc))
    (out / "views" / "side.svg").write_text("<svg/>")
    inode = out.stat().st_ino
    r = run("export", "SVG", "--out", str(out))
    assert r.returncode == 0, r.stderr
    assert out.stat().st_ino != inode and not (out / "views" / "side.svg").exists()
    assert (out / "views" / "iso.svg").is_file()
    files = sorted(p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file())
    assert sorted(json.loads(marker.read_text())["files"] + [".rig-cad-export"]) == files
    assert list(out.parent.iterdir()) == [out]


def test_an_older_export_without_a_manifest_falls_back_to_the_patterns(tmp_path):
    """An export from before the manifest (its marker is one line of text): the export's file patterns
    say what it may hold."""
    from cad.export_folder import foreign_files
    out = tmp_path / "old"
    (out / "views").mkdir(parents=True)
    (out / "printed").mkdir()
    (out / ".rig-cad-export").write_text("written by cad/build.py export; rig 431a\n")
    for f in ("rig_assembly.step", "camera_frames.json", "views/iso.svg", "printed/handle.stl"):
        (out / f).write_text("x")
    assert foreign_files(out) == []
    (out / "views" / "rig_assembly.glb").write_text("x")   # an export name, in the wrong folder
    (out / "notes.txt").write_text("mine")
    (out / "scans").mkdir()
    assert foreign_files(out) == [out / "notes.txt", out / "scans", out / "views" / "rig_assembly.glb"]


def test_a_file_added_while_exporting_stops_the_swap(tmp_path, monkeypatch):
    """The folder is checked again just before it is swapped: a file put there meanwhile is kept."""
    import argparse
    import cad.cli
    import cad.export
    from platform_tools.rig.conventions import UserError
    out = tmp_path / "out"
    out.mkdir()

    def fake_export(asm, stage, formats, tolerance, angular):
        (stage / "views").mkdir()
        (stage / "views" / "iso.svg").write_text("<svg/>")
        (out / "notes.txt").write_text("written during the export")
        return [stage / "views" / "iso.svg"]

    monkeypatch.setattr(cad.export, "export", fake_export)
    monkeypatch.setattr(cad.cli, "checked_rig", lambda args: None)
    monkeypatch.setattr(cad.cli, "assembly_from_args", lambda args, rig=None: None)
    args = argparse.Namespace(format="SVG", out=out, tolerance=0.1, angular_tolerance=0.2, json=False, quiet=True)
    with pytest.raises(UserError, match="notes.txt"):
        cad.cli.cmd_export(args)
    assert sorted(out.iterdir()) == [out / "notes.txt"] and list(tmp_path.iterdir()) == [out]


@pytest.mark.slow
def test_params_json_has_resolved_values():
    import json
    r = run("params", "--json", "--set", "enclosure.wall_mm=3")
    assert r.returncode == 0, r.stderr
    doc = json.loads(r.stdout)
    assert doc["rig"]["enclosure"]["wall_mm"] == 3
    assert doc["derived"]["case_outer_mm"]["size"][1] > 170
