"""zstd frames decompressed through the system's libzstd (platform_tools.dataset.libzstd), checked against frames
other encoders wrote (python-zstandard at several levels, with and without a content size; the zstd command-line
tool) and against python-zstandard's own decompression, which is also the fallback where the library is missing."""
from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest
import zstandard
from hypothesis import given, settings, strategies as st

from platform_tools.dataset import libzstd


@pytest.fixture
def no_system_library(monkeypatch):
    monkeypatch.setattr(libzstd, "_lib", False)


def _thermal_like(seed: int, n: int = 300_000) -> bytes:
    """16-bit noise around a smooth field: compresses about 2:1 as the Boson frames do (literals, short matches)."""
    rng = np.random.default_rng(seed)
    field = 7000 + 300 * np.sin(np.arange(n // 2) / 500.0)
    return (field + rng.normal(0, 20, n // 2)).astype("<u2").tobytes()


def test_the_system_library_is_the_one_used_here():
    # the bootstrap installs Debian's libzstd1; the speed this module exists for comes from it
    assert libzstd._load() is not None
    assert libzstd.backend().startswith("libzstd 1.") and libzstd.backend().endswith("(system)")


@pytest.mark.parametrize("level", [1, 3, 19])
@pytest.mark.parametrize("fallback", [False, True])
def test_frames_python_zstandard_wrote(level, fallback, monkeypatch):
    if fallback:
        monkeypatch.setattr(libzstd, "_lib", False)
        assert libzstd.backend().startswith("python-zstandard")
    raw = _thermal_like(level)
    frame = zstandard.ZstdCompressor(level=level).compress(raw)
    assert 1.3 < len(raw) / len(frame)
    got = libzstd.decompress(memoryview(b"xx" + frame)[2:], len(raw))     # a read-only view into a larger buffer
    assert bytes(got) == raw


def test_a_frame_without_a_content_size_and_the_command_line_tools_frame(tmp_path):
    raw = _thermal_like(5)
    streamed = zstandard.ZstdCompressor(write_content_size=False).compressobj()
    frame = streamed.compress(raw) + streamed.flush()
    assert bytes(libzstd.decompress(frame, len(raw))) == raw
    assert shutil.which("zstd"), "the bootstrap installs Debian's zstd"
    (tmp_path / "raw").write_bytes(raw)
    subprocess.run(["zstd", "-q", "-1", str(tmp_path / "raw"), "-o", str(tmp_path / "raw.zst")], check=True)
    assert bytes(libzstd.decompress((tmp_path / "raw.zst").read_bytes(), len(raw))) == raw


@settings(max_examples=60, deadline=None)
@given(st.binary(max_size=5000), st.integers(1, 9))
def test_any_bytes_come_back_as_python_zstandard_gives_them(raw, level):
    frame = zstandard.ZstdCompressor(level=level).compress(raw)
    got = libzstd.decompress(frame, len(raw))
    assert bytes(got) == raw == zstandard.ZstdDecompressor().decompress(frame, max_output_size=len(raw))


@pytest.mark.parametrize("fallback", [False, True])
def test_damage_and_a_wrong_size_are_one_line(fallback, monkeypatch):
    if fallback:
        monkeypatch.setattr(libzstd, "_lib", False)
    raw = _thermal_like(1)
    frame = bytearray(zstandard.ZstdCompressor(level=1).compress(raw))
    with pytest.raises(libzstd.ZstdError) as too_small:
        libzstd.decompress(bytes(frame), len(raw) - 1)
    with pytest.raises(libzstd.ZstdError) as cut:
        libzstd.decompress(bytes(frame[:len(frame) // 2]), len(raw))
    # zeros in a block's literals decode to other bytes without a checksum (mcap's chunk CRC is what catches those);
    # with one, zstd itself refuses them
    damaged = bytearray(zstandard.ZstdCompressor(level=1, write_checksum=True).compress(raw))
    damaged[len(damaged) // 2:len(damaged) // 2 + 64] = bytes(64)
    with pytest.raises(libzstd.ZstdError) as bad:
        libzstd.decompress(bytes(damaged), len(raw))
    with pytest.raises(libzstd.ZstdError) as not_zstd:
        libzstd.decompress(b"PNG, not zstd" * 10, 1000)
    for exc in (too_small, cut, bad, not_zstd):
        assert "\n" not in str(exc.value) and str(exc.value)
    # a frame holding less than was asked for comes back short: the caller compares (mcapscan.read_chunk does)
    assert bytes(libzstd.decompress(bytes(frame), len(raw) + 10)) == raw


@pytest.mark.parametrize("fallback", [False, True])
def test_a_prefix_is_the_first_bytes_of_the_content_and_no_more(fallback, monkeypatch):
    if fallback:
        monkeypatch.setattr(libzstd, "_lib", False)
    raw = _thermal_like(7, 600_000)
    frame = zstandard.ZstdCompressor(level=3).compress(raw)
    streamed = zstandard.ZstdCompressor(write_content_size=False).compressobj()
    unsized = streamed.compress(raw) + streamed.flush()
    two = zstandard.ZstdCompressor(level=1).compress(raw[:1000]) + frame      # two frames, one after the other
    for data, content in ((frame, raw), (unsized, raw), (two, raw[:1000] + raw)):
        for n in (1, 17, 1000, 1001, 131_072, 131_073, 400_000, len(content)):
            assert bytes(libzstd.decompress_prefix(memoryview(b"x" + data)[1:], n)) == content[:n]
        # the content ends first: what there is, the caller compares the length (mcapscan does)
        assert bytes(libzstd.decompress_prefix(data, len(content) + 5)) == content
    assert bytes(libzstd.decompress_prefix(frame, 0)) == b""


def test_one_context_serves_one_prefix_after_another_even_after_a_damaged_one():
    # the system library's context is kept per thread and reset before each use: a frame left half-read, or one
    # that failed, leaves nothing behind for the next
    a, b = _thermal_like(8), _thermal_like(9)
    fa, fb = (zstandard.ZstdCompressor(level=3).compress(x) for x in (a, b))
    assert bytes(libzstd.decompress_prefix(fa, 50_000)) == a[:50_000]
    with pytest.raises(libzstd.ZstdError):
        libzstd.decompress_prefix(b"not zstd at all" * 20, 100)
    assert bytes(libzstd.decompress_prefix(fb, 200_000)) == b[:200_000]
    assert bytes(libzstd.decompress_prefix(fa, len(a))) == a


@pytest.mark.parametrize("fallback", [False, True])
def test_a_damaged_prefix_is_one_line(fallback, monkeypatch):
    if fallback:
        monkeypatch.setattr(libzstd, "_lib", False)
    raw = _thermal_like(3)
    damaged = bytearray(zstandard.ZstdCompressor(level=1, write_checksum=True).compress(raw))
    damaged[20:84] = bytes(64)                  # the first block's header and literals
    with pytest.raises(libzstd.ZstdError) as bad:
        libzstd.decompress_prefix(bytes(damaged), len(raw))
    assert "\n" not in str(bad.value) and str(bad.value)


@settings(max_examples=60, deadline=None)
@given(st.binary(max_size=5000), st.integers(1, 9), st.integers(0, 6000))
def test_any_prefix_is_what_python_zstandard_gives(raw, level, n):
    frame = zstandard.ZstdCompressor(level=level).compress(raw)
    assert bytes(libzstd.decompress_prefix(frame, n)) == raw[:n]
