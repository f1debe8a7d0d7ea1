"""The check after stopping: the summary and every chunk's CRC, on files the mcap library wrote
(another writer than the check), with one flipped byte, and without CRCs (as zstd_fast writes)."""
from __future__ import annotations

from pathlib import Path

import pytest
from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer

from firmware.device import mcapcheck


def write(path: Path, *, crcs: bool = True, compression=CompressionType.ZSTD, n: int = 400) -> Path:
    with open(path, "wb") as f:
        w = Writer(f, chunk_size=16 * 1024, compression=compression, enable_crcs=crcs)
        w.start(profile="ros2", library="test")
        s = w.register_schema("std_msgs/msg/String", "ros2msg", b"string data")
        c = w.register_channel("/a", "cdr", s)
        for i in range(n):
            w.add_message(c, i * 1000, (b"frame %06d " % i) * 20, i * 1000, i)
        w.finish()
    return path


@pytest.mark.parametrize("compression", [CompressionType.ZSTD, CompressionType.LZ4, CompressionType.NONE])
def test_a_clean_file_verifies_every_chunk(tmp_path, compression):
    path = write(tmp_path / "a.mcap", compression=compression)
    status = mcapcheck.check_crcs(path)
    assert status.ok and status.error is None and status.messages == 400
    assert status.messages == mcapcheck.check(path).messages      # the old check, reading every message


def test_a_flipped_byte_in_a_chunk_fails(tmp_path):
    path = write(tmp_path / "a.mcap", compression=CompressionType.NONE)
    with open(path, "rb") as f:
        ci = make_reader(f).get_summary().chunk_indexes[1]
    data = bytearray(path.read_bytes())
    data[ci.chunk_start_offset + ci.chunk_length - 40] ^= 0xFF     # inside the chunk's records
    path.write_bytes(bytes(data))
    status = mcapcheck.check_crcs(path)
    assert not status.ok and "CRC" in status.error and str(ci.chunk_start_offset) in status.error


def test_chunks_without_crcs_are_readable_but_not_verified(tmp_path):
    status = mcapcheck.check_crcs(write(tmp_path / "a.mcap", crcs=False))
    assert status.ok and "carry no CRC (not verified)" in status.error


def test_a_file_without_summary_is_not_ok(tmp_path):
    path = write(tmp_path / "a.mcap")
    with open(path, "rb") as f:
        offset = make_reader(f).get_summary().chunk_indexes[-1].chunk_start_offset
    path.write_bytes(path.read_bytes()[:offset + 10])
    status = mcapcheck.check_crcs(path)
    assert not status.indexed and not status.ok


# ----------------------------------------------------------------------------- the levels (mcapverify)
import zlib  # noqa: E402

from hypothesis import given, settings, strategies as st  # noqa: E402
from mcap.stream_reader import CRCValidationError  # noqa: E402
from mcap.stream_reader import StreamReader  # noqa: E402

from firmware.device import mcapverify  # noqa: E402


@settings(max_examples=25, deadline=None)
@given(st.binary(max_size=300), st.binary(max_size=300))
def test_crc32_combine_is_zlibs_crc_of_the_concatenation(a, b):
    assert mcapverify.crc32_combine(zlib.crc32(a), zlib.crc32(b), len(b)) == zlib.crc32(a + b)


def write_with_data_crc(path: Path, n: int = 400) -> Path:
    with open(path, "wb") as f:
        w = Writer(f, chunk_size=16 * 1024, compression=CompressionType.ZSTD, enable_data_crcs=True)
        w.start(profile="ros2", library="test")
        s = w.register_schema("std_msgs/msg/String", "ros2msg", b"string data")
        c = w.register_channel("/a", "cdr", s)
        for i in range(n):
            w.add_message(c, i * 1000, (b"frame %06d " % i) * 20, i * 1000, i)
        w.finish()
    return path


def _mcap_library_says_ok(path: Path) -> bool:
    """The mcap library's own reader, validating every CRC it knows (the data section's included)."""
    try:
        with open(path, "rb") as f:
            for _ in StreamReader(f, validate_crcs=True).records:
                pass
        return True
    except CRCValidationError:
        return False


def test_every_level_on_a_file_with_a_data_crc(tmp_path):
    path = write_with_data_crc(tmp_path / "a.mcap")
    status = mcapverify.check_crcs(path, workers=1)
    assert status.ok and status.verified == ("summary", "data crc", "chunk crcs") and status.messages == 400
    assert _mcap_library_says_ok(path)
    # rosbag2's presets write no data CRC: the level is then simply not claimed
    assert mcapverify.check_crcs(write(tmp_path / "b.mcap"), workers=1).verified == ("summary", "chunk crcs")


def test_a_flipped_byte_between_chunks_is_caught_by_the_data_crc_only(tmp_path):
    """A byte of a message index (after a chunk, outside it): every chunk still matches its CRC, the data
    section's CRC does not, and the mcap library agrees."""
    path = write_with_data_crc(tmp_path / "a.mcap")
    with open(path, "rb") as f:
        ci = make_reader(f).get_summary().chunk_indexes[1]
    data = bytearray(path.read_bytes())
    data[ci.chunk_start_offset + ci.chunk_length + 20] ^= 0xFF        # a log time in the chunk's message index
    path.write_bytes(bytes(data))
    status = mcapverify.check_crcs(path, workers=1)
    assert not status.ok and status.error.startswith("data section CRC")
    assert not _mcap_library_says_ok(path)


def test_a_flipped_byte_in_the_summary_fails_the_summary_crc(tmp_path):
    """The message count of the Statistics record: the summary still parses, and says 144 (400 with bit 8 flipped)."""
    path = write(tmp_path / "a.mcap")
    data = bytearray(path.read_bytes())
    import struct
    pos = struct.unpack_from("<Q", data, len(data) - 8 - 20)[0]   # the footer's summary_start
    while data[pos] != 0x0B:                                      # walk the summary to Statistics
        pos += 9 + struct.unpack_from("<Q", data, pos + 1)[0]
    stats_at = pos
    data[stats_at + 9 + 1] ^= 0x01                              # message_count, second byte
    path.write_bytes(bytes(data))
    with open(path, "rb") as f:
        assert make_reader(f).get_summary().statistics.message_count == 400 ^ 256
    status = mcapverify.check_crcs(path, workers=1)
    assert not status.ok and "summary CRC" in status.error, status


@pytest.mark.slow
def test_worker_processes_give_the_same_verdicts(tmp_path):
    good = write_with_data_crc(tmp_path / "a.mcap", n=2000)
    one, four = mcapverify.check_crcs(good, workers=1), mcapverify.check_crcs(good, 4, min_parallel_bytes=0)
    assert one == four and four.ok and four.verified[-1] == "chunk crcs"
    bad = write(tmp_path / "b.mcap", compression=CompressionType.NONE, n=2000)
    with open(bad, "rb") as f:
        ci = make_reader(f).get_summary().chunk_indexes[-2]
    data = bytearray(bad.read_bytes())
    data[ci.chunk_start_offset + ci.chunk_length - 40] ^= 0xFF
    bad.write_bytes(bytes(data))
    status = mcapverify.check_crcs(bad, 3, min_parallel_bytes=0)
    assert not status.ok and f"chunk at byte {ci.chunk_start_offset}" in status.error


def test_the_data_crc_alone_proves_the_bytes_without_decompressing(tmp_path, monkeypatch):
    path = write_with_data_crc(tmp_path / "a.mcap")
    monkeypatch.setattr(mcapverify, "_decompress", lambda *a: (_ for _ in ()).throw(AssertionError("decompressed")))
    status = mcapverify.check_crcs(path, workers=1, chunks=False)
    assert status.ok and status.verified == ("summary", "data crc")
    monkeypatch.undo()
    plain = write(tmp_path / "b.mcap", compression=CompressionType.NONE)      # no data CRC: the chunks it is
    assert mcapverify.check_crcs(plain, workers=1, chunks=False).verified == ("summary", "chunk crcs")
