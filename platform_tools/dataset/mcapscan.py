"""An indexed MCAP file's messages read straight from its chunks: each chunk read and decompressed once, its records
walked in place, and each wanted message handed over as a ``memoryview`` of the decompressed chunk (no copy of its
data, no record objects). What the export's index and its workers need from a full-size recording, where mcap's
reader spent more time copying 1 MB images out of the chunks than zstd spent decompressing them (docs/dataset.md,
"Speed").

The order is mcap's own (``mcap.reader.SeekingReader.iter_messages``): by log time, ties by the chunk's offset in
the file, then by the message's place in its chunk (``log_time_order=True``), or chunk by chunk in file order
(``False``). A file without a chunk index (truncated, unindexed) is not for this module: :func:`has_chunk_index`
says so, and the caller uses mcap's reader. Specification: https://mcap.dev/spec (Chunk, Message records).
"""
from __future__ import annotations

import heapq
import struct

#: record opcodes (MCAP specification)
OP_MESSAGE = 0x05
OP_CHUNK = 0x06
#: opcode (1 byte) + record length (uint64)
RECORD_HEAD = 9
#: a Message record's fixed fields: channel_id u16, sequence u32, log_time u64, publish_time u64
_MESSAGE = struct.Struct("<HIQQ")
_U64 = struct.Struct("<Q")
_U32 = struct.Struct("<I")
#: a Chunk record's fixed fields: message_start_time, message_end_time, uncompressed_size u64; uncompressed_crc u32
_CHUNK = struct.Struct("<QQQI")


class ScanError(ValueError):
    """A chunk that cannot be read as the specification says (a damaged file); one line."""


def has_chunk_index(summary) -> bool:
    return summary is not None and len(summary.chunk_indexes) > 0


def _decompress(compression: str, data, size: int) -> bytes:
    if compression == "":
        return bytes(data)
    if compression == "zstd":
        import zstandard
        return zstandard.ZstdDecompressor().decompress(data, max_output_size=size)
    if compression == "lz4":
        import lz4.frame
        return lz4.frame.decompress(bytes(data))
    raise ScanError(f"chunk compression {compression!r} unknown (expected zstd, lz4 or none)")


def read_chunk(fh, chunk_index) -> bytes:
    """The decompressed records of the chunk ``chunk_index`` (an mcap ChunkIndex) of the open file ``fh``."""
    fh.seek(chunk_index.chunk_start_offset)
    raw = fh.read(chunk_index.chunk_length)
    if len(raw) != chunk_index.chunk_length or raw[0] != OP_CHUNK:
        raise ScanError(f"no chunk at offset {chunk_index.chunk_start_offset} (the file is shorter or damaged)")
    mv = memoryview(raw)
    try:
        _, _, size, _ = _CHUNK.unpack_from(raw, RECORD_HEAD)
        pos = RECORD_HEAD + _CHUNK.size
        (n,) = _U32.unpack_from(raw, pos)
        compression = bytes(mv[pos + 4:pos + 4 + n]).decode()
        pos += 4 + n
        (n,) = _U64.unpack_from(raw, pos)
        pos += 8
    except (struct.error, UnicodeDecodeError) as exc:
        raise ScanError(f"chunk at offset {chunk_index.chunk_start_offset}: bad header ({exc})") from None
    if pos + n > len(raw):
        raise ScanError(f"chunk at offset {chunk_index.chunk_start_offset}: records run past the chunk")
    try:
        out = _decompress(compression, mv[pos:pos + n], size)
    except ScanError:
        raise
    except Exception as exc:        # zstandard.ZstdError, lz4's RuntimeError: a damaged chunk
        raise ScanError(f"chunk at offset {chunk_index.chunk_start_offset}: {type(exc).__name__}: {exc}") from None
    if len(out) != size:
        raise ScanError(f"chunk at offset {chunk_index.chunk_start_offset}: {len(out)} bytes decompressed, "
                        f"{size} expected")
    return out


def messages(records: bytes, channel_ids) -> list[tuple[int, int, int, int, int]]:
    """``(log_time, place, channel_id, start, end)`` of every Message record of a chunk's ``records`` whose channel is
    in ``channel_ids``; ``place`` counts every record of the chunk (mcap's tie-break), ``records[start:end]`` is the
    message's data."""
    out = []
    pos, end, place = 0, len(records), 0
    try:
        while pos < end:
            (length,) = _U64.unpack_from(records, pos + 1)
            if records[pos] == OP_MESSAGE:
                channel, _, log_time, _ = _MESSAGE.unpack_from(records, pos + RECORD_HEAD)
                if channel in channel_ids:
                    start = pos + RECORD_HEAD + _MESSAGE.size
                    out.append((log_time, place, channel, start, pos + RECORD_HEAD + length))
            pos += RECORD_HEAD + length
            place += 1
    except struct.error:
        raise ScanError(f"a record at byte {pos} of a chunk runs past its end") from None
    if pos != end:
        raise ScanError(f"a record at byte {pos} of a chunk runs past its end")
    return out


def iter_messages(fh, summary, channel_ids, *, log_time_order: bool = True, chunks=None):
    """``(channel_id, log_time, data)`` of every message of the wanted channels, ``data`` a memoryview (valid while
    the caller holds it). ``chunks``: the chunk indexes to read (default: every one holding a wanted channel)."""
    wanted = set(channel_ids)
    if chunks is None:
        chunks = [c for c in summary.chunk_indexes if wanted & set(c.message_index_offsets)]
    if not log_time_order:
        for c in sorted(chunks, key=lambda c: c.chunk_start_offset):
            records = read_chunk(fh, c)
            view = memoryview(records)
            for log_time, _, channel, a, b in messages(records, wanted):
                yield channel, log_time, view[a:b]
        return
    # a chunk is opened when its first log time comes to the top, as in mcap's queue: (time, chunk offset, place)
    heap: list = [(c.message_start_time, c.chunk_start_offset, -1, 0, c) for c in chunks]
    heapq.heapify(heap)
    while heap:
        log_time, offset, place, channel, item = heapq.heappop(heap)
        if place < 0:
            records = read_chunk(fh, item)
            view = memoryview(records)
            for t, p, ch, a, b in messages(records, wanted):
                heapq.heappush(heap, (t, offset, p, ch, view[a:b]))
            continue
        yield channel, log_time, item
