"""Outputs are written whole or not at all."""
from __future__ import annotations

import os
from pathlib import Path

import pytest

from platform_tools.rig import atomic
from platform_tools.rig.atomic import OutputDir, OutputError, write_text


def test_output_dir_swaps_in_whole(tmp_path: Path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "old.txt").write_text("old")
    with OutputDir(out) as stage:
        (stage / "new.txt").write_text("new")
        assert not (out / "new.txt").exists()  # nothing visible until the block ends
    assert sorted(p.name for p in out.iterdir()) == ["new.txt"]
    assert [p.name for p in tmp_path.iterdir()] == ["out"]  # no staging or backup folders left


def test_output_dir_failure_leaves_previous_output(tmp_path: Path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "old.txt").write_text("old")
    with pytest.raises(RuntimeError):
        with OutputDir(out) as stage:
            (stage / "half.txt").write_text("half")
            raise RuntimeError("failed mid-way")
    assert sorted(p.name for p in out.iterdir()) == ["old.txt"]
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_output_dir_refuses_a_file(tmp_path: Path):
    f = tmp_path / "f"
    f.write_text("x")
    with pytest.raises(OutputError, match="not a folder"):
        with OutputDir(f):
            pass


def test_unwritable_place_is_an_output_error(tmp_path: Path):
    # /sys refuses new entries even to root: the error names the path instead of a traceback
    with pytest.raises(OutputError, match="/sys/rgbt-test"):
        with OutputDir(Path("/sys/rgbt-test")):
            pass
    with pytest.raises(OutputError, match="/sys/rgbt-test.txt"):
        write_text("/sys/rgbt-test.txt", "x")


def test_write_text_replaces_atomically(tmp_path: Path):
    p = tmp_path / "a" / "b.txt"
    write_text(p, "one")
    write_text(p, "two")
    assert p.read_text() == "two"
    assert [x.name for x in p.parent.iterdir()] == ["b.txt"]


def test_open_atomic_failure_mid_stream_leaves_nothing(tmp_path: Path):
    from platform_tools.rig.atomic import open_atomic
    target = tmp_path / "stream.bin"
    with pytest.raises(RuntimeError):
        with open_atomic(target) as f:
            f.write(b"partial")
            raise RuntimeError("died mid-write")
    assert list(tmp_path.iterdir()) == []


def _leftovers(folder):
    return sorted(p.name for p in folder.iterdir() if p.name.endswith(".tmp"))


def test_an_interrupt_just_after_the_temporary_is_created_removes_it(tmp_path, monkeypatch):
    """The window mkstemp left open: the file exists, its name not yet returned to the caller."""
    real_open = os.open

    def open_then_interrupt(path, flags, mode=0o777):
        fd = real_open(path, flags, mode)
        os.close(fd)
        raise KeyboardInterrupt
    monkeypatch.setattr(atomic.os, "open", open_then_interrupt)
    with pytest.raises(KeyboardInterrupt):
        write_text(tmp_path / "out.txt", "x")
    assert _leftovers(tmp_path) == []
    assert not (tmp_path / "out.txt").exists()


def test_someone_elses_file_with_the_temporary_name_is_never_removed(tmp_path, monkeypatch):
    names = iter(["aaaaaaaaaaaaaaaa", "bbbbbbbbbbbbbbbb"])
    monkeypatch.setattr(atomic.secrets, "token_hex", lambda n: next(names))
    theirs = tmp_path / ".out.txt.aaaaaaaaaaaaaaaa.tmp"
    theirs.write_text("not ours")
    write_text(tmp_path / "out.txt", "mine")
    assert theirs.read_text() == "not ours"
    assert (tmp_path / "out.txt").read_text() == "mine"
