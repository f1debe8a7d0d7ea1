"""bench/bench_dataset.py's comparison of two exports' files: a previous tree's PNG of a ZED image and this tree's
JPEG written as recorded are the same image when the JPEG, decoded as OpenCV decodes it, has the PNG's pixels."""
from __future__ import annotations

import cv2
import numpy as np

from tests.conftest import bench_module


def _bench():
    return bench_module("bench_dataset")


def test_a_png_and_the_jpeg_it_was_decoded_from_compare_by_pixels(tmp_path):
    rng = np.random.default_rng(3)
    img = cv2.GaussianBlur(rng.integers(0, 255, (40, 48, 3), dtype=np.uint8), (5, 5), 2)
    jpeg = cv2.imencode(".jpg", img)[1].tobytes()
    decoded = cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_COLOR)
    old, new = tmp_path / "old" / "rec" / "zed_left", tmp_path / "new" / "rec" / "zed_left"
    old.mkdir(parents=True)
    new.mkdir(parents=True)
    cv2.imwrite(str(old / "000000.png"), decoded)              # what the previous tree wrote
    (new / "000000.jpg").write_bytes(jpeg)                      # what this tree writes
    cv2.imwrite(str(old / "000001.png"), img)                   # not the JPEG's pixels: different
    (new / "000001.jpg").write_bytes(jpeg)
    (old / "000002.png").write_bytes((old / "000000.png").read_bytes())     # no JPEG beside it: only in previous
    got = _bench().compare_outputs(tmp_path / "old", tmp_path / "new")
    assert got["same_pixels_as_jpeg"] == ["rec/zed_left/000000.jpg"]
    assert got["different"] == ["rec/zed_left/000001.jpg"]
    assert got["only_in_previous"] == ["rec/zed_left/000002.png"] and got["only_in_new"] == []


def test_cold_runs_start_with_the_recording_out_of_the_page_cache_and_warm_ones_in_it(tmp_path):
    """--cold: evict() drops a recording's files from the page cache; util-linux's fincore (read back here on its
    own, not through evict's count) says none of their bytes are cached after it, where they all were before; and
    preload() (the runs without --cold) has them all cached again."""
    import os
    import shutil
    import subprocess
    if not shutil.which("fincore"):
        import pytest
        pytest.skip("util-linux's fincore is not installed")
    rec = tmp_path / "rec" / "bag"
    rec.mkdir(parents=True)
    for k in range(2):
        with open(rec / f"bag_{k}.mcap", "wb") as f:
            f.write(os.urandom(4 << 20))
            f.flush()
            os.fsync(f.fileno())                  # clean pages: what a long-written recording's are
        (rec / f"bag_{k}.mcap").read_bytes()

    def cached() -> int:
        out = subprocess.run(["fincore", "--bytes", "--noheadings", "--raw", "--output", "RES",
                              *map(str, sorted(rec.iterdir()))], capture_output=True, text=True, check=True).stdout
        return sum(int(x) for x in out.split())
    assert cached() >= 8 << 20
    assert _bench().evict(tmp_path / "rec") == 0
    assert cached() == 0
    assert _bench().preload(tmp_path / "rec") == 8 << 20 == cached()        # the runs without --cold: all cached


def test_the_paired_ratio_sees_each_repeat_on_its_own_machine_state():
    """A machine that slows by half for the second repeat: the best runs pair a fast new run with a slow old one
    (1.5 / 1 = 2x), the back-to-back pairs say 3x in both repeats; samples per second, so the counts weigh."""
    b = _bench()
    new_s, old_s = [10.0, 20.0], [30.0, 60.0]
    assert b.paired_median(new_s, old_s, 60, 60) == 3.0
    assert b.paired_median([10.0, 10.0, 12.0], [30.0, 40.0, 24.0], 61, 60) == (61 / 10.0) / (60 / 30.0)


def test_a_run_never_writes_into_nor_deletes_a_folder_that_exists(tmp_path):
    """Every timed run gets a new folder (bench_export's docstring: deleting a run's output just before the next made
    ext4 without a journal skip the freed inode numbers, 0.47 ms an openat); a folder already there is refused before
    anything runs, and left as it was."""
    import pytest
    out = tmp_path / "out-new-0"
    out.mkdir()
    (out / "kept.txt").write_text("a previous run's file")
    with pytest.raises(SystemExit, match="exists"):
        _bench().run_export(tmp_path / "tree", tmp_path / "rec", out, 1.0, 2)
    assert (out / "kept.txt").read_text() == "a previous run's file"


def test_a_bench_that_would_fill_the_disk_stops_before_its_timed_runs(tmp_path, monkeypatch):
    """The timed runs' outputs are kept until the bench ends: their size, scaled from the warm-up outputs, is checked
    against the free space first."""
    import collections
    import shutil
    import pytest
    for name in ("warm-b7c0534", "warm-new"):
        (tmp_path / name / "rec").mkdir(parents=True)
        (tmp_path / name / "rec" / "a.png").write_bytes(bytes(1000))
    Usage = collections.namedtuple("Usage", "total used free")
    b = _bench()
    monkeypatch.setattr(shutil, "disk_usage", lambda p: Usage(10 ** 9, 0, 50_000))
    # 2 trees x 1000 bytes, x4 for 1 Hz against the warm-up's 0.25 Hz, x5 repeats: 40,000 bytes
    assert b.check_room(tmp_path, [tmp_path / "warm-b7c0534", tmp_path / "warm-new"], 4.0, 5) == 40_000
    said = f"{tmp_path}: the timed runs would write about 0.4 MB .* 0.1 MB are free"
    with pytest.raises(SystemExit, match=said) as exc:
        b.check_room(tmp_path, [tmp_path / "warm-b7c0534", tmp_path / "warm-new"], 40.0, 5)    # 400,000 > 50,000
    assert "--repeats" in str(exc.value)
