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
