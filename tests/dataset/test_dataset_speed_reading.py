"""Reading a recording's MCAP summary once per process (recording.mcap_reader): the indexing, the size probe and
every chunk of a worker share it, and a file that changed is read again. The bags are written by the rosbags library
(tests/dataset/rosbags_rig.py), not by this project's simulator."""
from __future__ import annotations

import os
import shutil

import pytest
from mcap.reader import make_reader

from platform_tools.dataset import recording
from platform_tools.dataset.decode import iter_frames
from platform_tools.dataset.recording import mcap_files, mcap_reader, open_recording
from tests.dataset import rosbags_rig


pytestmark = pytest.mark.slow          # two bags written with rosbags (about 3 s)


@pytest.fixture(scope="module")
def written(tmp_path_factory, rig):
    """Two rosbags-written recordings of different lengths (so different summaries)."""
    out = {}
    for n in (60, 90):
        bag = tmp_path_factory.mktemp("bags") / f"bag{n}"
        rosbags_rig.write(bag, rosbags_rig.Spec(triggers=n, missing=(), drop=0.0, ffc={}),
                          rosbags_rig.project_layout(rig))
        out[n] = mcap_files(bag)[1][0]
    return out


@pytest.fixture()
def bags(written, tmp_path):
    """This test's copies of the two recordings (one may be changed), and no summary read yet."""
    out = {}
    for n, f in written.items():
        shutil.copytree(f.parent, tmp_path / f.parent.name)
        out[n] = tmp_path / f.parent.name / f.name
    recording._summaries.clear()
    return out


def _messages(reader) -> list[tuple[str, int, bytes]]:
    return [(c.topic, m.log_time, bytes(m.data)) for _, c, m in reader.iter_messages(log_time_order=True)]


def test_a_cached_summary_reads_the_same_messages_as_a_fresh_reader(bags):
    f = bags[60]
    with open(f, "rb") as fh:
        first = mcap_reader(fh, f)
        assert len(recording._summaries) == 1
        with open(f, "rb") as fh2:
            cached = mcap_reader(fh2, f)
            assert cached.get_summary() is first.get_summary()      # not read again
            with open(f, "rb") as fh3:
                assert _messages(cached) == _messages(make_reader(fh3))


def test_a_file_that_changed_is_read_again(bags):
    f, other = bags[60], bags[90]
    with open(f, "rb") as fh:
        n60 = mcap_reader(fh, f).get_summary().statistics.message_count
    shutil.copyfile(other, f)                                   # the same path now holds another recording
    os.utime(f, ns=(os.stat(f).st_atime_ns, os.stat(f).st_mtime_ns + 1_000_000))
    with open(f, "rb") as fh:
        n90 = mcap_reader(fh, f).get_summary().statistics.message_count
    with open(other, "rb") as fh:
        assert n90 == make_reader(fh).get_summary().statistics.message_count != n60


def test_indexing_and_decoding_read_each_summary_once(bags, rig, monkeypatch):
    reads = []
    real = recording._summaries.__class__.__setitem__

    class Counting(dict):
        def __setitem__(self, k, v):
            reads.append(k)
            real(self, k, v)

    monkeypatch.setattr(recording, "_summaries", Counting())
    rec = open_recording(bags[90].parent, rig)
    st = rec.streams["thermal_left"]
    wanted = {(st.topic, int(s)): i for i, s in enumerate(st.stamp_ns[:5])}
    got = list(iter_frames([str(bags[90])], wanted, [int(x) for x in st.log_ns[:5]]))
    assert sorted(w for w, _, _ in got) == list(range(5))
    assert reads == [(str(bags[90]), os.stat(bags[90]).st_size, os.stat(bags[90]).st_mtime_ns)]


def test_only_a_few_summaries_are_kept(bags, monkeypatch):
    monkeypatch.setattr(recording, "SUMMARIES_KEPT", 1)
    for f in (bags[60], bags[90], bags[60]):
        with open(f, "rb") as fh:
            mcap_reader(fh, f)
    assert list(recording._summaries) == [(str(bags[60]), os.stat(bags[60]).st_size, os.stat(bags[60]).st_mtime_ns)]
