"""The export's reading and writing pieces: the read windows (decode.windows), the PNG level (chunk.png_bytes),
the temporary files a stopped worker leaves and which of them a resumed export removes (export.remove_partial)."""
from __future__ import annotations

import cv2
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from platform_tools.dataset.chunk import _write_png, tmp_name
from platform_tools.dataset.decode import windows
from platform_tools.dataset.export import remove_partial


@st.composite
def chunk_index(draw):
    """Chunk spans as a sequential writer makes them (each after the last, some gaps), sometimes one overlapping
    its predecessor (a writer flushing topics separately), and wanted times in and between them."""
    spans, t = [], 0
    for _ in range(draw(st.integers(0, 12))):
        t += draw(st.integers(0, 50))
        a = t - (draw(st.integers(0, 30)) if spans and draw(st.booleans()) else 0)
        t += draw(st.integers(0, 40))
        spans.append((a, t))
    times = draw(st.lists(st.integers(-5, t + 5), max_size=30))
    return spans, times


def _chunks_read(w, spans):
    """The chunks the mcap reader decompresses for each window: those whose span overlaps it."""
    return [i for a, b in w for i, (s0, s1) in enumerate(spans) if s0 <= b and s1 >= a]


@settings(max_examples=120, deadline=None)
@given(chunk_index())
def test_windows_read_every_needed_chunk_once_and_nothing_else(case):
    spans, times = case
    w = windows(times, spans)
    assert all(a <= b for a, b in w) and all(b0 < a1 for (_, b0), (a1, _) in zip(w, w[1:]))   # ordered, disjoint
    for t in times:                                     # every wanted time is read
        assert sum(a <= t <= b for a, b in w) == 1
    read = _chunks_read(w, spans)
    needed = {i for i, (a, b) in enumerate(spans) for t in times if a <= t <= b}
    assert needed <= set(read)
    if all(a1 > b0 for (_, b0), (a1, _) in zip(spans, spans[1:])):    # a sequential file: exactly those, once
        assert sorted(read) == sorted(needed)


def test_windows_at_one_hertz_read_only_each_samples_chunks():
    # chunks of 16 ms back to back; five messages per sample within 40 ms; samples 1 s apart
    spans = [(k * 16_000_000, k * 16_000_000 + 15_999_999) for k in range(250)]
    logs = [s * 10**9 + k * 10**7 for s in range(4) for k in range(5)]
    w = windows(logs, spans)
    holding = sorted({t // 16_000_000 for t in logs})                      # the chunks holding a wanted message
    assert _chunks_read(w, spans) == holding and len(w) == 4 and len(holding) <= 4 * 4
    # one window from the first to the last sample (the previous read) would have decompressed 191 chunks
    assert len(_chunks_read([(min(logs), max(logs))], spans)) == 3_040 // 16 + 1


def test_png_level_changes_the_bytes_not_the_pixels(tmp_path):
    rng = np.random.default_rng(1)
    img16 = (np.add.outer(np.arange(120), np.arange(160)) * 40 + rng.integers(0, 50, (120, 160))).astype(np.uint16)
    sizes = {}
    for level in (None, 0, 9):
        path = tmp_path / f"{level}.png"
        _write_png(path, img16, level)
        back = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
        assert back.dtype == np.uint16 and np.array_equal(back, img16)
        sizes[level] = path.stat().st_size
    assert sizes[0] > sizes[None] and sizes[0] > sizes[9]          # level 0 stores, the others compress
    assert not list(tmp_path.glob(".*"))                              # no temporary file left


def test_a_resumed_export_removes_only_a_writers_temporary_files(tmp_path):
    rec = tmp_path / "rec" / "thermal_left" / "8bit"
    rec.mkdir(parents=True)
    partial = tmp_name(rec / "000003.png", 4242)
    partial.write_bytes(b"half")
    zed = tmp_path / "rec" / "zed_left"
    zed.mkdir()
    jpeg = tmp_name(zed / "000003.jpg", 4243)          # a recorded JPEG being written (zed_images as_recorded)
    jpeg.write_bytes(b"half")
    kept = [rec / "000003.png", rec / "notes.tmp", rec / ".000003.png.tmp", tmp_path / "other" / ".000001.png.7.tmp",
            zed / ".000003.gif.4243.tmp"]
    for k in kept:
        k.parent.mkdir(parents=True, exist_ok=True)
        k.write_bytes(b"mine")
    assert sorted(remove_partial(tmp_path, ["rec"])) == sorted([partial, jpeg])
    assert not partial.exists() and not jpeg.exists() and all(k.read_bytes() == b"mine" for k in kept)
