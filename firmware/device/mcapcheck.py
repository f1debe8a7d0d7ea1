"""Check an MCAP file after a recording stops, and recover it when its summary (index) is missing.

The check after a stop is `check_crcs` (firmware/device/mcapverify.py: the summary, the data section CRC
and the chunk CRCs, in parallel, no message parsed); `check` reads every message (the old check).

An MCAP whose writer was killed (SIGKILL, power loss, a crash) has no footer or summary, and may end
in the middle of a record. :func:`recover` reads it record by record from the start, keeps every
schema, channel and message up to the first damaged record (whole chunks only, CRC-checked), and
writes them to ``<name>.recovered.mcap`` next to the original, which is never modified.
"""
from __future__ import annotations

import struct
from dataclasses import dataclass
from pathlib import Path

from mcap.exceptions import McapError
from mcap.reader import make_reader
from mcap.records import Channel, Chunk, Message, Schema
from mcap.stream_reader import StreamReader, breakup_chunk
from mcap.writer import CompressionType, Writer

# the check after a stop lives in mcapverify; its names are here too for the recorder and the tests
from firmware.device.mcapverify import ChunkError, McapStatus, check_crcs, verify_chunk  # noqa: F401
from platform_tools.rig.atomic import open_atomic

RECOVERED_SUFFIX = ".recovered.mcap"


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
