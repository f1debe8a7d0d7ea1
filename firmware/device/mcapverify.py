"""The check after a recording stops, without parsing a message: what the MCAP format lets a reader
prove from its summary and its CRCs, the work spread over worker processes.

Levels, each proving more (McapStatus.verified names the ones a file passed):

- ``summary``     the footer and the summary section read, and the Footer's ``summary_crc`` matches the
                  summary bytes: the index (chunk offsets, statistics) a reader relies on is intact.
                  Milliseconds: a few kB read.
- ``data crc``    the DataEnd record's ``data_section_crc`` matches the CRC-32 of every raw byte from the
                  start of the file to DataEnd: every byte on the drive is the byte the writer wrote (no
                  decompression). Computed in pieces in parallel and combined (`crc32_combine`). Only when
                  the writer computed it (non-zero: the mcap writers' ``enable_data_crcs`` /
                  ``enableDataCRC``; rosbag2's presets leave it 0).
- ``chunk crcs``  every chunk the summary indexes decompresses to the bytes its ``uncompressed_crc`` was
                  computed over: the compressed payload decodes to the writer's records. The costly
                  level (zstd), spread over workers by contiguous runs of chunks.

A chunk without CRC (0: the ``zstd_fast`` preset) is readable but not verified (the error says so).
"""
from __future__ import annotations

import multiprocessing
import os
import struct
import zlib
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

from mcap.exceptions import McapError
from mcap.reader import make_reader

#: record opcodes and fixed layouts of the MCAP spec
CHUNK_OPCODE, DATA_END_OPCODE, FOOTER_OPCODE = 0x06, 0x0F, 0x02
MAGIC = b"\x89MCAP0\r\n"
_RECORD_HEAD = struct.Struct("<BQ")
_CHUNK_HEAD = struct.Struct("<QQQI")       # message start/end time, uncompressed size, uncompressed crc
_FOOTER = struct.Struct("<BQQQI")          # opcode, length (20), summary_start, summary_offset_start, crc
_DATA_END = struct.Struct("<BQI")          # opcode, length (4), data_section_crc
#: bytes each worker reads per call when hashing the data section
_READ = 1 << 22
#: below this many bytes the check runs in this process: starting workers costs more than it saves
PARALLEL_MIN_BYTES = 256 * 1024 * 1024


@dataclass(frozen=True)
class McapStatus:
    path: str
    indexed: bool          # has a footer with a summary section
    readable: bool         # every message can be read
    messages: int
    error: str | None = None
    verified: tuple[str, ...] = ()     # the levels above this file passed

    @property
    def ok(self) -> bool:
        return self.indexed and self.readable

    def to_dict(self) -> dict:
        return {"path": self.path, "indexed": self.indexed, "readable": self.readable,
                "messages": self.messages, "error": self.error, "verified": list(self.verified)}


class ChunkError(ValueError):
    """A chunk that is not where the summary says, or whose content does not match its CRC."""


# ----------------------------------------------------------------------------- CRC-32 arithmetic
def _gf2_times(mat: list[int], vec: int) -> int:
    out, i = 0, 0
    while vec:
        if vec & 1:
            out ^= mat[i]
        vec >>= 1
        i += 1
    return out


def _gf2_square(mat: list[int]) -> list[int]:
    return [_gf2_times(mat, mat[n]) for n in range(32)]


def crc32_combine(crc1: int, crc2: int, len2: int) -> int:
    """CRC-32 of A + B from crc32(A), crc32(B) and len(B) (zlib's crc32_combine, which Python's zlib
    does not expose): lets workers hash pieces of a file and the results be joined in order."""
    if len2 <= 0:
        return crc1
    odd = [0xEDB88320] + [1 << n for n in range(31)]    # the operator for one zero bit
    even = _gf2_square(odd)                              # two zero bits
    odd = _gf2_square(even)                              # four
    while True:
        even = _gf2_square(odd)                          # apply len2 zero bytes to crc1, by squaring
        if len2 & 1:
            crc1 = _gf2_times(even, crc1)
        len2 >>= 1
        if not len2:
            break
        odd = _gf2_square(even)
        if len2 & 1:
            crc1 = _gf2_times(odd, crc1)
        len2 >>= 1
        if not len2:
            break
    return crc1 ^ crc2


# ----------------------------------------------------------------------------- one chunk (pure)
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


# ----------------------------------------------------------------------------- worker tasks
def _chunks_task(path: str, spans: list[tuple[int, int]]) -> tuple[int, int, str | None]:
    """(verified, without CRC, first error) over chunks at (offset, length), read in file order."""
    verified = unverified = 0
    with open(path, "rb") as f:
        for offset, length in spans:
            f.seek(offset)
            try:
                if verify_chunk(f.read(length)):
                    verified += 1
                else:
                    unverified += 1
            except (ChunkError, struct.error, UnicodeDecodeError, ValueError) as exc:
                return verified, unverified, f"chunk at byte {offset}: {exc}"
    return verified, unverified, None


def _crc_task(path: str, start: int, end: int) -> int:
    crc = 0
    with open(path, "rb") as f:
        f.seek(start)
        left = end - start
        while left > 0:
            block = f.read(min(_READ, left))
            if not block:
                raise ChunkError(f"file ends at byte {end - left}, before the data section's end {end}")
            crc = zlib.crc32(block, crc)
            left -= len(block)
    return crc


def _runs(items: list, n: int) -> list[list]:
    """`items` cut into at most n contiguous runs of near-equal length."""
    n = max(1, min(n, len(items)))
    size, extra = divmod(len(items), n)
    out, i = [], 0
    for k in range(n):
        j = i + size + (k < extra)
        out.append(items[i:j])
        i = j
    return [r for r in out if r]


# ----------------------------------------------------------------------------- the file
def _tail(f, size: int) -> tuple[int, int, int, int]:
    """(footer offset, summary_start, summary_crc, data_end offset), from the file's last bytes."""
    footer_at = size - len(MAGIC) - _FOOTER.size
    f.seek(footer_at)
    opcode, length, summary_start, _, summary_crc = _FOOTER.unpack(f.read(_FOOTER.size))
    if opcode != FOOTER_OPCODE or length != _FOOTER.size - _RECORD_HEAD.size or f.read(len(MAGIC)) != MAGIC:
        raise ChunkError("no footer at the end of the file")
    data_end_at = (summary_start or footer_at) - _DATA_END.size
    return footer_at, summary_start, summary_crc, data_end_at


def check_crcs(path: Path, workers: int | None = None, min_parallel_bytes: int = PARALLEL_MIN_BYTES,
               chunks: bool = True) -> McapStatus:
    """Every level above, the data CRC's pieces and the chunk runs in `workers` processes (default: one
    per CPU; 1, or a file under `min_parallel_bytes`: in this process). Reads the summary and each chunk
    once; no message record is parsed. ``chunks=False`` stops at the data CRC when the file has one (no
    decompression: every byte proven, not that the chunks decompress)."""
    path = Path(path)
    workers = workers or os.cpu_count() or 1
    if path.stat().st_size < min_parallel_bytes:
        workers = 1
    try:
        with open(path, "rb") as f:
            summary = make_reader(f).get_summary()
            if summary is None:
                return McapStatus(str(path), False, False, 0, "no summary section")
            size = os.fstat(f.fileno()).st_size
            footer_at, summary_start, summary_crc, data_end_at = _tail(f, size)
            verified = []
            if summary_crc:
                f.seek(summary_start)
                got = zlib.crc32(f.read(footer_at + _FOOTER.size - 4 - summary_start))
                if got != summary_crc:
                    return McapStatus(str(path), False, False, 0,
                                      f"summary CRC {got:08x}, the footer says {summary_crc:08x}")
            verified.append("summary")
            f.seek(data_end_at)
            opcode, length, data_crc = _DATA_END.unpack(f.read(_DATA_END.size))
            if opcode != DATA_END_OPCODE or length != 4:
                return McapStatus(str(path), True, False, 0, f"no DataEnd record at byte {data_end_at}")
        expected = summary.statistics.message_count if summary.statistics else 0
        spans = sorted((ci.chunk_start_offset, ci.chunk_length) for ci in summary.chunk_indexes)
        if not chunks and data_crc:
            spans = []
        return _verify(path, spans, data_crc, data_end_at, workers, expected, verified)
    except (McapError, ChunkError, ValueError, EOFError, OSError, struct.error) as exc:
        return McapStatus(str(path), False, False, 0, f"{type(exc).__name__}: {exc}")


def _verify(path: Path, spans, data_crc: int, data_end_at: int, workers: int, expected: int,
            verified: list[str]) -> McapStatus:
    cuts = [round(data_end_at * k / workers) for k in range(workers + 1)] if data_crc else []
    pieces = list(zip(cuts, cuts[1:]))
    runs = _runs(spans, workers)
    if workers == 1:
        crcs = [_crc_task(str(path), a, b) for a, b in pieces]
        results = [_chunks_task(str(path), r) for r in runs]
    else:
        # forkserver: the recorder has threads (the button loop); forking it would copy their locks
        ctx = multiprocessing.get_context("forkserver")
        with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
            crc_futures = [pool.submit(_crc_task, str(path), a, b) for a, b in pieces]
            chunk_futures = [pool.submit(_chunks_task, str(path), r) for r in runs]
            crcs = [fu.result() for fu in crc_futures]
            results = [fu.result() for fu in chunk_futures]
    if data_crc:
        got = 0
        for (a, b), c in zip(pieces, crcs):
            got = crc32_combine(got, c, b - a)
        if got != data_crc:
            return McapStatus(str(path), True, False, 0, f"data section CRC {got:08x}, DataEnd says {data_crc:08x}")
        verified.append("data crc")
    errors = [e for _, _, e in results if e]
    if errors:
        return McapStatus(str(path), True, False, 0, errors[0], tuple(verified))
    if not spans:
        return McapStatus(str(path), True, True, expected, None, tuple(verified))
    unverified = sum(u for _, u, _ in results)
    if unverified:
        return McapStatus(str(path), True, True, expected,
                          f"{unverified} of {len(spans)} chunks carry no CRC (not verified)", tuple(verified))
    return McapStatus(str(path), True, True, expected, None, (*verified, "chunk crcs"))
