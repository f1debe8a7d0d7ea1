"""What the index keeps of each message of one MCAP file, read chunk by chunk: in runs of chunks side by side in the
export's pool workers when it has them (:func:`scan_file`), else here.

Of a rig stream's message: its header stamp; of a thermal frame also a digest of the last TAIL_BYTES of its image rows
(two consecutive frames with equal digests: a frozen frame, the FFC), its Boson telemetry frame counter and FFC state.
Of an FFC status message what the index keeps of it (:func:`.ffcstatus.read`, decoded here: in the workers, while
they scan); of the other wanted topics (camera_info: small messages) the data itself, for the caller to decode.

From an uncompressed chunk (rosbags writes them) a thermal frame is read in part (:class:`.mcapscan.Sparse`): its
fields, then one read of the rows holding its tail and its telemetry rows; a ZED image only for its stamp.

Why in parts: from a compressed chunk the thermal frames are read whole (their tails and telemetry rows end them),
and decompressing them is most of an index's time (2.75 of 4.6 s of CPU on this project's simulated 60 s
full-size recording, docs/dataset.md "Speed"), while the export's workers would wait for the plan. Every event
carries its place in mcap's order (:func:`.mcapscan.iter_keyed`), so the parts merge back into the order one scan
reads: the index is the same however the chunks were split (tests/dataset/test_dataset_indexscan.py).
"""
from __future__ import annotations

import hashlib
import heapq
import struct
from dataclasses import dataclass, field
from pathlib import Path

from .cdr import STAMP_BYTES, header_stamp, image_layout
from .mcapscan import Sparse

#: the bytes at the end of a thermal frame's image rows compared to find frozen frames
TAIL_BYTES = 4096
#: runs of chunks per pool worker: more parts even out the workers' shares (a run of cheap ZED chunks beside one
#: of thermal ones) at the cost of one task each
PARTS_PER_WORKER = 4
#: runs of chunks scanned one after another without a pool: the progress bar's steps
SERIAL_PARTS = 16
#: the digest of a tail (blake2b): 16 bytes sent back per frame instead of TAIL_BYTES
DIGEST_BYTES = 16
#: the bytes of a thermal frame read first from an uncompressed chunk (mcapscan.Sparse): its CDR header and Image
#: fields (a frame_id longer than this is read whole); the tail and the telemetry rows are read after them
FIELDS_BYTES = 256


@dataclass(frozen=True)
class Wanted:
    """What :func:`scan_part` reads, by topic."""
    streams: dict                 # topic -> rig stream ("zed_left", "thermal_left", ...): stamp (and tail) read
    others: frozenset             # topics whose whole data is returned (status, camera_info)
    stamps_only: frozenset        # stream topics of which only the header stamp is read (STAMP_BYTES)
    telemetry_rows: int           # rig: Boson telemetry rows below a thermal image (on_device.thermal_telemetry_rows)
    model_px: tuple               # the thermal camera model's (width, height), to tell whether a frame has them
    status: dict = field(default_factory=dict)  # of ``others``: FFC status topic -> its type (ffcstatus.check_type's)

    def topics(self) -> set:
        return set(self.streams) | set(self.others)


def rows_below(rows: int, model_px: tuple, width: int, height: int) -> int:
    """How many of the rig's ``rows`` Boson telemetry rows (platform_tools.boson.telemetry) a thermal frame of
    ``width`` x ``height`` px carries below its image, for a camera model of ``model_px`` (width, height): ``rows``
    or 0."""
    from platform_tools.boson.telemetry import telemetry_rows_present
    return rows if telemetry_rows_present(width, height, model_px[0], model_px[1], rows) else 0


def thermal_fields(data, wanted: Wanted, rows_cache: dict) -> tuple[bytes, int, int]:
    """(digest of the last TAIL_BYTES of a thermal frame's image rows, its telemetry frame counter or -1, its telemetry
    FFC state or -1) of a CDR sensor_msgs/Image (bytes, a memoryview, or an :class:`.mcapscan.Sparse` of which only
    the fields, the tail and the telemetry rows are read); a frame whose fields cannot be read: the digest of its last
    TAIL_BYTES, -1, -1."""
    from platform_tools.boson.telemetry import TelemetryError, decode_image_data
    if isinstance(data, Sparse):
        head, read = data.head, data.read
    else:
        head, read = data, lambda a, b: data[a:b]
    size = len(data)
    try:
        try:
            height, width, step, off = image_layout(head, size)
        except (struct.error, ValueError, IndexError):
            if len(head) == size:
                raise
            head = read(0, size)                # fields longer than the head read (a long frame_id): read it all
            height, width, step, off = image_layout(head, size)
    except (struct.error, ValueError, IndexError):
        return _digest(read(max(0, size - TAIL_BYTES), size)), -1, -1
    if (width, height) not in rows_cache:
        rows_cache[(width, height)] = rows_below(wanted.telemetry_rows, wanted.model_px, width, height)
    rows = rows_cache[(width, height)]
    # one read from a row's start: the image rows holding the tail, then the telemetry rows
    above = min(height - rows, -(-TAIL_BYTES // step)) if step > 0 else 0
    first = off + (height - rows - above) * step
    blob = memoryview(read(first, off + height * step))
    counter = ffc = -1
    if rows:
        try:
            tel = decode_image_data(blob, above + rows, step, rows)
            counter, ffc = int(tel.frame_counter), int(tel.ffc_status)
        except TelemetryError:
            pass
    return _digest(blob[max(0, above * step - TAIL_BYTES):above * step]), counter, ffc


def _digest(tail) -> bytes:
    return hashlib.blake2b(tail, digest_size=DIGEST_BYTES).digest()


def event(log_time: int, offset: int, place: int, topic: str, data, wanted: Wanted, rows_cache: dict) -> tuple:
    """One message as the index keeps it: ``(log_time, offset, place, topic, stamp, digest, counter, ffc)`` for a rig
    stream (``digest`` None, ``counter`` and ``ffc`` -1 but for thermal frames), ``(log_time, offset, place, topic,
    ffcstatus.StatusRead)`` for an FFC status, ``(log_time, offset, place, topic, data bytes)`` for the others;
    ValueError for a status message cut short."""
    stream = wanted.streams.get(topic)
    if stream is None:
        if topic in wanted.status:
            from .ffcstatus import read
            return log_time, offset, place, topic, read(wanted.status[topic], data)
        return log_time, offset, place, topic, bytes(data)
    stamp = header_stamp(data.head if isinstance(data, Sparse) else data)
    if not stream.startswith("thermal"):
        return log_time, offset, place, topic, stamp, None, -1, -1
    return (log_time, offset, place, topic, stamp) + thermal_fields(data, wanted, rows_cache)


def scan_part(path: str, channels: dict, wanted: Wanted, chunks: list) -> list[tuple]:
    """The :func:`event` of every wanted message in the ``chunks`` (mcap ChunkIndex records) of the MCAP file at
    ``path``, in mcap's order; ``channels``: channel id -> topic, the wanted ones. Run in a pool worker or here.
    Errors: the scan's (mcapscan.ScanError, a ValueError) and the file's (OSError)."""
    from . import mcapscan
    from .workers import keep_freed_memory
    keep_freed_memory()                 # each chunk's buffers reuse the last one's pages (workers.keep_freed_memory)
    heads = {cid: STAMP_BYTES for cid, t in channels.items() if t in wanted.stamps_only}
    sparse = {cid: FIELDS_BYTES for cid, t in channels.items()
              if wanted.streams.get(t, "").startswith("thermal") and cid not in heads}
    rows_cache: dict = {}
    with open(path, "rb") as fh:
        return [event(t, off, place, channels[cid], data, wanted, rows_cache)
                for t, off, place, cid, data in mcapscan.iter_keyed(fh, None, channels, chunks=chunks, heads=heads,
                                                                     sparse=sparse)]


#: the sizes of a pool's last runs of chunks, against the others': halving, so that the workers end their scans close
#: together (the pool hands the runs out in order; the last worker to end its scan then loads its kernels while the
#: samples wait: docs/dataset.md "Speed")
TAIL_WEIGHTS = (0.5, 0.5, 0.25, 0.25)


def parts(chunks: list, n: int) -> list[list]:
    """The chunks in file order cut into at most ``n`` contiguous runs of about equal uncompressed size, but the last
    four (with ``n`` of 8 or more: :data:`TAIL_WEIGHTS` of the others')."""
    chunks = sorted(chunks, key=lambda c: c.chunk_start_offset)
    total = sum(c.uncompressed_size for c in chunks) or 1
    weights = [1.0] * n if n < 2 * len(TAIL_WEIGHTS) else [1.0] * (n - len(TAIL_WEIGHTS)) + list(TAIL_WEIGHTS)
    bounds = [total * sum(weights[:k + 1]) / sum(weights) for k in range(n)]
    out, run, acc = [], [], 0
    for c in chunks:
        run.append(c)
        acc += c.uncompressed_size
        if acc >= bounds[len(out)] and len(out) < n - 1:
            out.append(run)
            run = []
    if run:
        out.append(run)
    return out


def scan_file(path, summary, wanted: Wanted, pool=None):
    """The :func:`event` of every wanted message of an indexed MCAP file (``summary``: its mcap Summary, with chunk
    indexes), in mcap's log-time order (an iterator over the runs' lists, merged as it is read); ``pool``: an
    :class:`.engines.Pool` whose workers scan runs of chunks side by side (``pool.map``), else the runs are scanned
    here one after another. A progress bar counts the chunks."""
    from platform_tools.rig.progress import progress
    channels = {cid: c.topic for cid, c in summary.channels.items() if c.topic in wanted.topics()}
    chunks = [c for c in summary.chunk_indexes if channels.keys() & set(c.message_index_offsets)]
    runs = parts(chunks, SERIAL_PARTS if pool is None else PARTS_PER_WORKER * pool.workers)
    args = [(str(path), channels, wanted, run) for run in runs]
    bar = progress(range(len(chunks)), desc=f"index {Path(path).name}", total=len(chunks), unit="chunk")
    try:
        if pool is None or len(runs) < 2:
            results = []
            for a in args:
                results.append(scan_part(*a))
                bar.update(len(a[3]))
        else:
            results = pool.map(scan_part, args, done=lambda k: bar.update(len(runs[k])))
    finally:
        bar.close()
    return heapq.merge(*results)


def scan_reader(reader, wanted: Wanted) -> tuple[list[tuple], dict]:
    """:func:`scan_file` for a file without a chunk index (recovered, unindexed), through mcap's reader, here; with
    the schema of each topic read (topic -> mcap Schema)."""
    rows_cache: dict = {}
    events, schemas = [], {}
    for i, (schema, channel, msg) in enumerate(reader.iter_messages(topics=sorted(wanted.topics()),
                                                                    log_time_order=True)):
        schemas.setdefault(channel.topic, schema)
        events.append(event(msg.log_time, 0, i, channel.topic, msg.data, wanted, rows_cache))
    return events, schemas
