"""An indexed MCAP file's messages read straight from its chunks: each chunk read and decompressed once, its records
walked in place, and each wanted message handed over as a ``memoryview`` of the decompressed chunk (no copy of its
data, no record objects). What the export's index and its workers need from a full-size recording, where mcap's
reader spent more time copying 1 MB images out of the chunks than zstd spent decompressing them (docs/dataset.md,
"Speed").

The order is mcap's own (``mcap.reader.SeekingReader.iter_messages``): by log time, ties by the chunk's offset in
the file, then by the message's place in its chunk (``log_time_order=True``), or chunk by chunk in file order
(``False``). A file without a chunk index (truncated, unindexed) is not for this module: :func:`has_chunk_index`
says so, and the caller uses mcap's reader. Specification: https://mcap.dev/spec (Chunk, Message, MessageIndex
records).

Where only a message's first bytes are wanted (``heads``: the export's index reads a ZED image's or depth map's
header stamp, nothing else), a zstd chunk with a message index is decompressed only up to the last byte wanted of
it, when that ends before PREFIX_FRACTION of its records: the message index (written after each chunk) says where
each message starts. On this project's simulated full-size recording (20 s) the index then decompresses 981 of
2,359 MB; its scan takes 7 % less CPU (the thermal frames, read whole for their tails and telemetry, are most of
the decompression's time; the ZED chunks it skips compress well and decompress fast).

An uncompressed chunk (what rosbags writes, and rosbag2's MCAP writer where compression does not pay) needs no
decompressing to reach a message: there each wanted message is read from the file in part (:func:`_sparse_messages`)
when what is wanted of the chunk is less than PREFIX_FRACTION of it. A channel in ``heads`` gives its first bytes, a
channel in ``sparse`` a :class:`Sparse` (the message's first bytes, the rest read on demand: a thermal frame's
telemetry rows and tail at its end), the other wanted channels their whole data. The records between them are not
read, so not checked either; every message read is checked against its message index.
"""
from __future__ import annotations

import heapq
import io
import os
import struct

from platform_tools.dataset import libzstd

#: record opcodes (MCAP specification)
OP_MESSAGE = 0x05
OP_CHUNK = 0x06
OP_MESSAGE_INDEX = 0x07
#: opcode (1 byte) + record length (uint64)
RECORD_HEAD = 9
#: a Message record's fixed fields: channel_id u16, sequence u32, log_time u64, publish_time u64
_MESSAGE = struct.Struct("<HIQQ")
_U64 = struct.Struct("<Q")
_U32 = struct.Struct("<I")
#: a Chunk record's fixed fields: message_start_time, message_end_time, uncompressed_size u64; uncompressed_crc u32
_CHUNK = struct.Struct("<QQQI")
#: a MessageIndex record's fixed fields: channel_id u16, then the byte length u32 of its (log_time u64, offset u64) pairs
_MESSAGE_INDEX = struct.Struct("<HI")
#: a Message record's bytes before its data
MESSAGE_HEAD = RECORD_HEAD + _MESSAGE.size


class ScanError(ValueError):
    """A chunk that cannot be read as the specification says (a damaged file); one line."""


def has_chunk_index(summary) -> bool:
    return summary is not None and len(summary.chunk_indexes) > 0


def _decompress(compression: str, data, size: int) -> bytes | memoryview:
    if compression == "":
        return bytes(data)
    if compression == "zstd":
        return libzstd.decompress(data, size)
    if compression == "lz4":
        import lz4.frame
        return lz4.frame.decompress(bytes(data))
    raise ScanError(f"chunk compression {compression!r} unknown (expected zstd, lz4 or none)")


def _chunk_records(fh, chunk_index) -> tuple[str, memoryview, int]:
    """(compression, the compressed records, their uncompressed size) of the chunk ``chunk_index`` of ``fh``."""
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
    return compression, mv[pos:pos + n], size


def read_chunk(fh, chunk_index) -> bytes | memoryview:
    """The decompressed records of the chunk ``chunk_index`` (an mcap ChunkIndex) of the open file ``fh``."""
    compression, data, size = _chunk_records(fh, chunk_index)
    try:
        out = _decompress(compression, data, size)
    except ScanError:
        raise
    except Exception as exc:        # libzstd.ZstdError, lz4's RuntimeError: a damaged chunk
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
                    start = pos + MESSAGE_HEAD
                    out.append((log_time, place, channel, start, pos + RECORD_HEAD + length))
            pos += RECORD_HEAD + length
            place += 1
    except struct.error:
        raise ScanError(f"a record at byte {pos} of a chunk runs past its end") from None
    if pos != end:
        raise ScanError(f"a record at byte {pos} of a chunk runs past its end")
    return out


def message_index(fh, chunk_index, channel_ids) -> list[tuple[int, int, int]] | None:
    """``(offset, log_time, channel_id)`` of the messages of ``channel_ids`` in one chunk, by their offset in the
    chunk's uncompressed records, read from the MessageIndex records written after the chunk (no decompression);
    None when the chunk has no message index."""
    ids = [cid for cid in channel_ids if cid in chunk_index.message_index_offsets]
    if not ids or chunk_index.message_index_length <= 0:
        return None
    base = chunk_index.chunk_start_offset + chunk_index.chunk_length
    fh.seek(base)
    raw = fh.read(chunk_index.message_index_length)
    where = f"the message index of the chunk at offset {chunk_index.chunk_start_offset}"
    out = []
    for cid in ids:
        pos = chunk_index.message_index_offsets[cid] - base
        try:
            if pos < 0 or raw[pos] != OP_MESSAGE_INDEX:
                raise ScanError(f"{where}: no MessageIndex record for channel {cid} at byte {pos + base}")
            channel, n = _MESSAGE_INDEX.unpack_from(raw, pos + RECORD_HEAD)
            entries = struct.unpack_from(f"<{n // 8}Q", raw, pos + RECORD_HEAD + _MESSAGE_INDEX.size)
        except (struct.error, IndexError):
            raise ScanError(f"{where}: channel {cid}'s record runs past the index") from None
        if channel != cid or n % 16:
            raise ScanError(f"{where}: channel {cid}'s record is damaged")
        out += [(entries[k + 1], entries[k], cid) for k in range(0, len(entries), 2)]
    out.sort()
    return out


#: a chunk is decompressed only in part when what is wanted of it ends before this fraction of its records
PREFIX_FRACTION = 0.5


def _wanted_ends(every, size: int, wanted, cut: dict) -> list[tuple[int, int, int]]:
    """``(offset, channel_id, end)`` of each wanted message of a chunk, by offset (``every``: the chunk's message
    index, every channel's; ``size``: its records' bytes): ``end``, where what is wanted of the message ends at most,
    is after its first ``cut[channel]`` bytes of data, or the next message's start (or the records' end)."""
    bounds = [e[0] for e in every[1:]] + [size]
    return [(off, cid, min(b, off + MESSAGE_HEAD + cut[cid]) if cid in cut else b)
            for (off, _, cid), b in zip(every, bounds) if cid in wanted]


def _message_head(buf, pos: int, offset: int, cid: int, where: str) -> tuple[int, int]:
    """(record length, log time) of the Message record at ``buf[pos:]``, checked to be channel ``cid``'s, as the
    chunk's message index says (which puts it at byte ``offset`` of the records)."""
    try:
        if buf[pos] != OP_MESSAGE:
            raise IndexError
        (length,) = _U64.unpack_from(buf, pos + 1)
        channel, _, log_time, _ = _MESSAGE.unpack_from(buf, pos + RECORD_HEAD)
    except (struct.error, IndexError):
        raise ScanError(f"{where}: no Message record at byte {offset}, where its message index says") from None
    if channel != cid:
        raise ScanError(f"{where}: the Message record at byte {offset} is not what its message index says")
    return length, log_time


def _prefix_messages(fh, chunk_index, wanted, heads, stats):
    """``(log_time, offset, channel, data)`` of the chunk's wanted messages, by offset, its zstd records decompressed
    only up to the last byte wanted: a channel in ``heads`` gives at most ``heads[channel]`` bytes of each message's
    data. None where that would not save much (what is wanted ends past PREFIX_FRACTION of the records) or cannot
    be done (no message index, another compression, no message in ``heads``)."""
    if chunk_index.compression != "zstd" or not heads.keys() & set(chunk_index.message_index_offsets):
        return None
    every = message_index(fh, chunk_index, chunk_index.message_index_offsets)
    if every is None:
        return None
    size = chunk_index.uncompressed_size
    index = _wanted_ends(every, size, wanted, heads)
    need = max(end for _, _, end in index)
    if need > PREFIX_FRACTION * size:
        return None
    _, data, _ = _chunk_records(fh, chunk_index)
    where = f"chunk at offset {chunk_index.chunk_start_offset}"
    try:
        buf = libzstd.decompress_prefix(data, need)
    except libzstd.ZstdError as exc:            # a damaged chunk
        raise ScanError(f"{where}: ZstdError: {exc}") from None
    if len(buf) < need:
        raise ScanError(f"{where}: the records end at byte {len(buf)}, before their stated size")
    out = []
    for offset, cid, _ in index:
        start = offset + MESSAGE_HEAD
        if start > need:
            raise ScanError(f"{where}: no Message record at byte {offset}, where its message index says")
        length, log_time = _message_head(buf, offset, offset, cid, where)
        end = offset + RECORD_HEAD + length
        if cid in heads:
            end = min(end, start + heads[cid])
        if end > need:
            raise ScanError(f"{where}: the Message record at byte {offset} is not what its message index says")
        out.append((log_time, offset, cid, buf[start:end]))
    stats["decompressed_bytes"] = stats.get("decompressed_bytes", 0) + need
    return out


def _pread(fh, at: int, n: int) -> bytes:
    """Up to ``n`` bytes of ``fh`` from byte ``at``: ``os.pread`` on a file, seek and read on another stream."""
    try:
        fd = fh.fileno()
    except (AttributeError, io.UnsupportedOperation):
        fh.seek(at)
        return fh.read(n)
    return os.pread(fd, n, at)


class Sparse:
    """A message's data read in part: its first bytes (``head``), any other bytes read from the file when asked
    (:meth:`read`), while the file is open. ``len()`` is the whole data's."""

    __slots__ = ("head", "_size", "_fh", "_at", "_where")

    def __init__(self, head: bytes, size: int, fh, at: int, where: str):
        self.head, self._size, self._fh, self._at, self._where = head, size, fh, at, where

    def __len__(self) -> int:
        return self._size

    def read(self, a: int, b: int) -> bytes:
        """Bytes ``a:b`` of the message's data (0 <= a <= b <= len)."""
        if not 0 <= a <= b <= self._size:
            raise ScanError(f"{self._where}: bytes {a}:{b} asked of a message of {self._size}")
        if b <= len(self.head):
            return self.head[a:b]
        got = _pread(self._fh, self._at + a, b - a)
        if len(got) != b - a:
            raise ScanError(f"{self._where}: the file ends inside the message")
        return got


def _records_at(fh, chunk_index, where: str) -> int:
    """The file offset of an uncompressed chunk's records, from its header (checked against its chunk index)."""
    head = _pread(fh, chunk_index.chunk_start_offset, RECORD_HEAD + _CHUNK.size + 4 + 8)
    pos = RECORD_HEAD + _CHUNK.size                 # then the compression's name (empty: u32 0), the records' length
    try:
        if head[0] != OP_CHUNK:
            raise ScanError(f"{where}: no chunk there (the file is shorter or damaged)")
        _, _, size, _ = _CHUNK.unpack_from(head, RECORD_HEAD)
        (n,) = _U32.unpack_from(head, pos)
        (length,) = _U64.unpack_from(head, pos + 4)
    except (struct.error, IndexError):
        raise ScanError(f"{where}: bad header (the file is shorter or damaged)") from None
    if n != 0 or size != chunk_index.uncompressed_size or length != size:
        raise ScanError(f"{where}: its header is not what its chunk index says")
    return chunk_index.chunk_start_offset + pos + 4 + 8


def _sparse_messages(fh, chunk_index, wanted, heads, sparse, stats):
    """``(log_time, offset, channel, data)`` of an uncompressed chunk's wanted messages, by offset, each read from the
    file in part: a channel in ``heads`` gives at most ``heads[channel]`` bytes of each message's data (bytes), a
    channel in ``sparse`` a :class:`Sparse` with at most ``sparse[channel]`` bytes read, the others their whole data.
    None where that would not save much (what is wanted is more than PREFIX_FRACTION of the records) or cannot be
    done (a compressed chunk, no message index, no message in ``heads`` or ``sparse``)."""
    cut = heads.keys() | sparse.keys()
    if chunk_index.compression != "" or not cut & set(chunk_index.message_index_offsets):
        return None
    every = message_index(fh, chunk_index, chunk_index.message_index_offsets)
    if every is None:
        return None
    size = chunk_index.uncompressed_size
    index = _wanted_ends(every, size, wanted, heads | sparse)
    if sum(end - off for off, _, end in index) > PREFIX_FRACTION * size:
        return None
    where = f"chunk at offset {chunk_index.chunk_start_offset}"
    at = _records_at(fh, chunk_index, where)
    out, read = [], 0
    for offset, cid, upto in index:
        n = upto - offset
        buf = _pread(fh, at + offset, n)
        read += len(buf)
        length, log_time = _message_head(buf, 0, offset, cid, where)
        end = RECORD_HEAD + length                      # the record's end, from its start
        if length < _MESSAGE.size or offset + end > size:
            raise ScanError(f"{where}: the Message record at byte {offset} is not what its message index says")
        if cid in sparse:
            data = Sparse(buf[MESSAGE_HEAD:min(end, n)], end - MESSAGE_HEAD, fh, at + offset + MESSAGE_HEAD, where)
        elif cid in heads:
            data = buf[MESSAGE_HEAD:min(end, n)]
        else:
            if end > n:
                raise ScanError(f"{where}: the Message record at byte {offset} runs into the next one")
            data = buf[MESSAGE_HEAD:end]
        out.append((log_time, offset, cid, data))
    stats["read_bytes"] = stats.get("read_bytes", 0) + read
    return out


def _chunk_messages(fh, chunk_index, wanted, heads, stats, sparse=None):
    """``(log_time, place, channel, data)`` of one chunk's wanted messages in record order (``place`` increases with
    it), through :func:`_sparse_messages` or :func:`_prefix_messages` where they apply, else by decompressing the
    whole chunk. ``sparse`` ({channel: n}, see :func:`_sparse_messages`): a channel of which an uncompressed chunk
    gives a :class:`Sparse`; a compressed one gives its whole data."""
    if heads or sparse:
        got = _sparse_messages(fh, chunk_index, wanted, heads, sparse or {}, stats)
        if got is not None:
            return got
    if heads:
        got = _prefix_messages(fh, chunk_index, wanted, heads, stats)
        if got is not None:
            return got
    records = read_chunk(fh, chunk_index)
    stats["decompressed_bytes"] = stats.get("decompressed_bytes", 0) + len(records)
    view = memoryview(records)
    return [(t, p, ch, view[a:b]) for t, p, ch, a, b in messages(records, wanted)]


def iter_messages(fh, summary, channel_ids, *, log_time_order: bool = True, chunks=None, heads=None, stats=None,
                  sparse=None):
    """``(channel_id, log_time, data)`` of every message of the wanted channels, ``data`` a memoryview (valid while
    the caller holds it). ``chunks``: the chunk indexes to read (default: every one holding a wanted channel).
    ``heads``: {channel_id: n} for channels of which only the first ``n`` bytes of each message's data are wanted (a
    header stamp): a zstd chunk with a message index is then decompressed only up to the last byte wanted of it,
    which skips most of a chunk of large images; an uncompressed chunk's messages are read in part from the file.
    ``sparse``: {channel_id: n} for channels of which an uncompressed chunk gives a :class:`Sparse` (the first ``n``
    bytes read, the rest on demand) in place of the data. ``stats``: a dict that gets ``decompressed_bytes`` and
    ``read_bytes`` (read in part)."""
    for log_time, _, _, channel, data in iter_keyed(fh, summary, channel_ids, log_time_order=log_time_order,
                                                    chunks=chunks, heads=heads, stats=stats, sparse=sparse):
        yield channel, log_time, data


def iter_keyed(fh, summary, channel_ids, *, log_time_order: bool = True, chunks=None, heads=None, stats=None,
               sparse=None):
    """As :func:`iter_messages`, each message as ``(log_time, chunk offset, place, channel_id, data)``: the first three
    are its place in mcap's order (log time, ties by the chunk's offset in the file, then by the record's place in its
    chunk), so that messages read from different runs of chunks merge back into that order (``heapq.merge``).
    ``summary`` is only read when ``chunks`` is None."""
    wanted = set(channel_ids)
    heads = {cid: n for cid, n in (heads or {}).items() if cid in wanted}
    sparse = {cid: n for cid, n in (sparse or {}).items() if cid in wanted and cid not in heads}
    stats = {} if stats is None else stats
    if chunks is None:
        chunks = [c for c in summary.chunk_indexes if wanted & set(c.message_index_offsets)]
    if not log_time_order:
        for c in sorted(chunks, key=lambda c: c.chunk_start_offset):
            for log_time, place, channel, data in _chunk_messages(fh, c, wanted, heads, stats, sparse):
                yield log_time, c.chunk_start_offset, place, channel, data
        return
    # a chunk is opened when its first log time comes to the top, as in mcap's queue: (time, chunk offset, place)
    heap: list = [(c.message_start_time, c.chunk_start_offset, -1, 0, c) for c in chunks]
    heapq.heapify(heap)
    while heap:
        log_time, offset, place, channel, item = heapq.heappop(heap)
        if place < 0:
            for t, p, ch, data in _chunk_messages(fh, item, wanted, heads, stats, sparse):
                heapq.heappush(heap, (t, offset, p, ch, data))
            continue
        yield log_time, offset, place, channel, item
