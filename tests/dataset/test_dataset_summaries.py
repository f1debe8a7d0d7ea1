"""recording.read_summaries: an export reads its recordings' MCAP summaries once, before forking its workers; a
worker then finds them in the cache it inherited, whatever spelling of the path its task carries (the tasks carry
resolved paths, a user may type a relative one or go through a symlink)."""
from __future__ import annotations

import os

import mcap.reader
import pytest

from platform_tools.dataset import recording

#: every test reads the simulated recording (one exports it): the quick loop (make test-fast) leaves them to make test
pytestmark = pytest.mark.slow


@pytest.fixture
def parses(monkeypatch):
    """The count of summaries parsed from a file (mcap's SeekingReader.get_summary called with none cached)."""
    count = [0]
    original = mcap.reader.SeekingReader.get_summary

    def counted(self):
        if getattr(self, "_summary", None) is None:
            count[0] += 1
        return original(self)
    monkeypatch.setattr(mcap.reader.SeekingReader, "get_summary", counted)
    monkeypatch.setattr(recording, "_summaries", {})
    return count


def _open(path):
    with open(path, "rb") as fh:
        return recording.mcap_reader(fh, path).get_summary()



def test_a_summary_read_once_serves_every_spelling_of_the_path(sim, tmp_path, monkeypatch, parses):
    _, files = recording.mcap_files(sim[0])
    real = files[0].resolve()
    link = tmp_path / "link.mcap"
    link.symlink_to(real)
    monkeypatch.chdir(real.parent)
    recording.read_summaries(sim[0])
    assert parses[0] == 1
    for spelling in (real, os.path.relpath(real), link):
        assert len(_open(spelling).chunk_indexes) > 0
    assert parses[0] == 1


def test_the_export_has_read_the_summaries_when_it_forks_its_workers(sim, rig, tmp_path, monkeypatch, parses):
    from platform_tools.dataset import export as ex
    _, files = recording.mcap_files(sim[0])
    seen = []
    original = ex.started

    def started(*a, **k):
        seen.append([os.path.realpath(k[0]) for k in recording._summaries])
        return original(*a, **k)
    monkeypatch.setattr(ex, "started", started)
    ex.export([sim[0]], tmp_path / "ds", rig, ex.Params.from_rig(rig, rate_hz=0.5), engine="inline")
    assert seen == [[str(f.resolve()) for f in files]]
    assert parses[0] == len(files)                      # and read once in all: the index took them from the cache


def test_an_unreadable_recording_is_left_for_open_recording_to_report(tmp_path, parses):
    (tmp_path / "bag_0.mcap").write_bytes(b"not an mcap")
    recording.read_summaries(tmp_path)                 # quiet
    recording.read_summaries(tmp_path / "missing")     # quiet
    with pytest.raises(recording.RecordingError):
        recording.open_recording(tmp_path / "missing", None)
