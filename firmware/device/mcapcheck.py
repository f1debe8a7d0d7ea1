"""Check an MCAP file after a recording stops, and recover it when its summary (index) is missing.

An MCAP whose writer was killed (SIGKILL, power loss, a crash) has no footer or summary, and may end
in the middle of a record. :func:`recover` reads it record by record from the start, keeps every
schema, channel and message up to the first damaged record (whole chunks only, CRC-checked), and
writes them to ``<name>.recovered.mcap`` next to the original, which is never modified.
"""
from __future__ import annotations

import struct
import zlib
from dataclasses import dataclass
from pathlib import Path

from mcap.exceptions import McapError
from mcap.reader import make_reader
from mcap.records import Channel, Chunk, Message, Schema
from mcap.stream_reader import StreamReader, breakup_chunk
from mcap.writer import CompressionType, Writer

from platform_tools.rig.atomic import open_atomic

RECOVERED_SUFFIX = ".recovered.mcap"


@dataclass(frozen=True)
class McapStatus:
    path: str
    indexed: bool          # has a footer with a summary section
    readable: bool         # every message can be read
    messages: int
    error: str | None = None

    @property
    def ok(self) -> bool:
        return self.indexed and self.readable

    def to_dict(self) -> dict:
        return {"path": self.path, "indexed": self.indexed, "readable": self.readable,
                "messages": self.messages, "error": self.error}


#: the MCAP Chunk record's opcode, and the fixed part of its body before the compression string:
#: message_start_time u64, message_end_time u64, uncompressed_size u64, uncompressed_crc u32
CHUNK_OPCODE = 0x06
_CHUNK_HEAD = struct.Struct("<QQQI")
_RECORD_HEAD = struct.Struct("<BQ")


class ChunkError(ValueError):
    """A chunk that is not where the summary says, or whose content does not match its CRC."""


def _decompress(compression: str, data: bytes, size: int) -> bytes:
    if compression == "":
        return data
    if compression == "zstd":
        import zstandard
        return zstandard.ZstdDecompressor().decompress(data, max_output_size=size)
    if compression == "lz4":
        import lz4.frame
        return lz4.frame.decompress(data)
    raise ChunkError(f"unknown chunk compression {compression!r}")


def verify_chunk(record: bytes) -> bool:
    """Check one Chunk record (opcode, length, body) against its CRC. True when verified, False when
    the writer wrote no CRC (0: zstd_fast); ChunkError when it does not match."""
    opcode, length = _RECORD_HEAD.unpack_from(record)
    if opcode != CHUNK_OPCODE or length != len(record) - _RECORD_HEAD.size:
        raise ChunkError(f"not a whole chunk record (opcode {opcode:#x}, length {length})")
    pos = _RECORD_HEAD.size
    _, _, size, crc = _CHUNK_HEAD.unpack_from(record, pos)
    pos += _CHUNK_HEAD.size
    (n,) = struct.unpack_from("<I", record, pos)
    compression = record[pos + 4:pos + 4 + n].decode()
    pos += 4 + n
    (records_len,) = struct.unpack_from("<Q", record, pos)
    data = _decompress(compression, record[pos + 8:pos + 8 + records_len], size)
    if len(data) != size:
        raise ChunkError(f"decompressed to {len(data)} bytes, the chunk says {size}")
    if crc == 0:
        return False
    if zlib.crc32(data) != crc:
        raise ChunkError(f"CRC {zlib.crc32(data):08x}, the chunk says {crc:08x}")
    return True


def check_crcs(path: Path) -> McapStatus:
    """Is the file complete, and does every chunk the summary indexes match its CRC? Reads the summary
    and each chunk once; no message record is parsed. A file whose chunks carry no CRC is readable
    but not verified (the error says so)."""
    try:
        with open(path, "rb") as f:
            summary = make_reader(f).get_summary()
            if summary is None:
                return McapStatus(str(path), False, False, 0, "no summary section")
            expected = summary.statistics.message_count if summary.statistics else 0
            unverified = 0
            for ci in summary.chunk_indexes:
                f.seek(ci.chunk_start_offset)
                record = f.read(ci.chunk_length)
                try:
                    unverified += not verify_chunk(record)
                except (ChunkError, struct.error, UnicodeDecodeError) as exc:
                    return McapStatus(str(path), True, False, 0, f"chunk at byte {ci.chunk_start_offset}: {exc}")
            if unverified:
                return McapStatus(str(path), True, True, expected,
                                  f"{unverified} of {len(summary.chunk_indexes)} chunks carry no CRC (not verified)")
            return McapStatus(str(path), True, True, expected)
    except (McapError, ValueError, EOFError, OSError, struct.error) as exc:
        return McapStatus(str(path), False, False, 0, f"{type(exc).__name__}: {exc}")


def check(path: Path) -> McapStatus:
    """Is the file complete (summary present) and does every message read? (Reads every message:
    `check_crcs` is what runs after a recording stops.)"""
    try:
        with open(path, "rb") as f:
            reader = make_reader(f)
            summary = reader.get_summary()
            if summary is None:
                return McapStatus(str(path), False, False, 0, "no summary section")
            expected = summary.statistics.message_count if summary.statistics else None
            n = sum(1 for _ in reader.iter_messages(log_time_order=False))
            if expected is not None and n != expected:
                return McapStatus(str(path), True, False, n, f"read {n} messages, the summary says {expected}")
            return McapStatus(str(path), True, True, n)
    except (McapError, ValueError, EOFError, OSError, struct.error) as exc:
        return McapStatus(str(path), False, False, 0, f"{type(exc).__name__}: {exc}")


@dataclass(frozen=True)
class Recovered:
    source: str
    path: str
    messages: int
    stopped_at: str | None   # why reading stopped before the end (the damage), None when it reached the end

    def to_dict(self) -> dict:
        return {"source": self.source, "path": self.path, "messages": self.messages, "stopped_at": self.stopped_at}


def _salvage(path: Path):
    """Yield schemas, channels and messages in file order until the first damaged record."""
    with open(path, "rb") as f:
        try:
            for record in StreamReader(f, skip_magic=False, validate_crcs=True).records:
                if isinstance(record, Chunk):
                    for inner in breakup_chunk(record, validate_crc=True):
                        yield inner
                elif isinstance(record, (Schema, Channel, Message)):
                    yield record
        except Exception as exc:  # noqa: BLE001  any damage ends the salvage; the reason is kept
            yield exc


def recover(path: Path) -> Recovered:
    """Write ``<name>.recovered.mcap`` next to `path` with everything readable in it."""
    path = Path(path)
    target = path.with_name(path.name[:-len(".mcap")] + RECOVERED_SUFFIX if path.name.endswith(".mcap")
                            else path.name + RECOVERED_SUFFIX)
    schema_ids: dict[int, int] = {}
    channel_ids: dict[int, int] = {}
    n, stopped = 0, None
    with open_atomic(target) as out:
        writer = Writer(out, compression=CompressionType.ZSTD)
        writer.start(profile="ros2", library="rgbt-rig mcap recover")
        for rec in _salvage(path):
            if isinstance(rec, Exception):
                stopped = f"{type(rec).__name__}: {rec}"
                break
            if isinstance(rec, Schema) and rec.id not in schema_ids:
                schema_ids[rec.id] = writer.register_schema(rec.name, rec.encoding, rec.data)
            elif isinstance(rec, Channel) and rec.id not in channel_ids:
                if rec.schema_id == 0 or rec.schema_id in schema_ids:
                    channel_ids[rec.id] = writer.register_channel(
                        rec.topic, rec.message_encoding, schema_ids.get(rec.schema_id, 0), dict(rec.metadata))
            elif isinstance(rec, Message) and rec.channel_id in channel_ids:
                writer.add_message(channel_ids[rec.channel_id], rec.log_time, rec.data, rec.publish_time,
                                   rec.sequence)
                n += 1
        writer.finish()
    return Recovered(str(path), str(target), n, stopped)


def is_recovered_copy(path: Path) -> bool:
    return path.name.endswith(RECOVERED_SUFFIX)
