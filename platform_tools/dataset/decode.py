"""Decode a recording's image messages (``sensor_msgs/Image`` and ``CompressedImage`` in MCAP, ROS 2 CDR) into
numpy arrays: (H, W) mono / depth, (H, W, 3) BGR uint8."""
from __future__ import annotations

import bisect
import itertools
from dataclasses import dataclass

import cv2
import numpy as np

from . import mcapscan
from .recording import Recording, compressed_fields, header_stamp, image_fields, mcap_reader

#: the streams the export reads images of
IMAGE_STREAMS = ("zed_left", "zed_right", "zed_depth", "thermal_left", "thermal_right")


#: ROS image encoding -> (numpy dtype, channels)
ENCODINGS = {"mono16": (np.uint16, 1), "16UC1": (np.uint16, 1), "32FC1": (np.float32, 1), "mono8": (np.uint8, 1),
             "8UC1": (np.uint8, 1), "bgr8": (np.uint8, 3), "rgb8": (np.uint8, 3), "bgra8": (np.uint8, 4)}


#: the first bytes of the image files a CompressedImage may hold that the export writes as they are -> their suffix
MAGIC_SUFFIX = {b"\xff\xd8\xff": ".jpg", b"\x89PNG\r\n\x1a\n": ".png"}


@dataclass(frozen=True)
class Encoded:
    """A CompressedImage's image file as the recording holds it (a JPEG or a PNG, ``suffix``), and its format
    string (``jpeg``, ``bgr8; jpeg compressed bgr8``...)."""
    data: bytes
    format: str
    suffix: str

    def image(self) -> np.ndarray:
        """The decoded image, as :func:`decode_cdr` gives it."""
        return _compressed(self.data, self.format)


def encoded(data, fmt: str) -> Encoded | None:
    """The :class:`Encoded` of a CompressedImage's ``data`` (bytes or a memoryview) in format ``fmt``; None when
    it is not a file MAGIC_SUFFIX knows (compressedDepth's header, another codec)."""
    head = bytes(data[:8])
    for magic, suffix in MAGIC_SUFFIX.items():
        if head.startswith(magic):
            return Encoded(bytes(data), fmt, suffix)
    return None


def _compressed(buf, fmt: str) -> np.ndarray:
    img = cv2.imdecode(np.frombuffer(buf, np.uint8), cv2.IMREAD_UNCHANGED)
    if img is None:
        raise ValueError(f"undecodable {fmt} image")
    return cv2.cvtColor(img, cv2.COLOR_GRAY2BGR) if img.ndim == 2 else img[..., :3]


def _raw(buf, height: int, width: int, encoding: str, bigendian: bool, step: int, offset: int = 0) -> np.ndarray:
    if encoding not in ENCODINGS:
        raise ValueError(f"unsupported image encoding {encoding!r}")
    dt, ch = ENCODINGS[encoding]
    dt = np.dtype(dt).newbyteorder(">" if bigendian else "<")
    row = np.frombuffer(buf, np.uint8, count=height * step, offset=offset).reshape(height, step)
    # a copy (writable, owning its pixels) even where the rows are contiguous in the message
    img = row[:, :width * ch * dt.itemsize].copy().view(dt).reshape(height, width, ch)
    if not dt.isnative:
        img = img.astype(dt.newbyteorder("="))
    if encoding == "rgb8":
        img = img[..., ::-1]
    return img[..., 0] if ch == 1 else np.ascontiguousarray(img[..., :3])


def decode_cdr(schema_name: str, data) -> np.ndarray:
    """The image of a CDR-serialised ``sensor_msgs/Image`` or ``CompressedImage`` (bytes or a memoryview), decoded
    from the message's bytes where they lie (one copy of a raw image's pixels, none of a compressed one's): the
    same array as :func:`decode_image` of the message mcap_ros2 deserialises."""
    if schema_name.endswith("CompressedImage"):
        fmt, offset, n = compressed_fields(data)
        return _compressed(data[offset:offset + n], fmt)
    height, width, encoding, bigendian, step, offset = image_fields(data)
    return _raw(data, height, width, encoding, bigendian, step, offset)


def decode_image(schema_name: str, msg) -> np.ndarray:
    """The image of a message as mcap_ros2 deserialises it (fields ``data``, ``format`` or ``encoding``...)."""
    if schema_name.endswith("CompressedImage"):
        return _compressed(bytes(msg.data), msg.format)
    return _raw(bytes(msg.data), msg.height, msg.width, msg.encoding, msg.is_bigendian, msg.step)


def windows(log_ns, spans) -> list[tuple[int, int]]:
    """The log-time windows to read so that every MCAP chunk holding a wanted message is decompressed once and no
    other chunk of a sequentially written file is: ``spans`` are the chunks' (message_start_time, message_end_time)
    (the file's chunk index), ``log_ns`` the wanted messages' log times. Each window is one needed chunk's span, or
    several needed chunks' spans merged where they overlap. A time in no chunk's span (no index) gets its own
    one-instant window."""
    spans = sorted((int(a), int(b)) for a, b in spans)
    starts = [a for a, _ in spans]
    reach = list(itertools.accumulate((b for _, b in spans), max))     # the latest end among spans[:i + 1]
    need: set[int] = set()
    loose: list[tuple[int, int]] = []
    for t in {int(x) for x in log_ns}:
        hit = False
        i = bisect.bisect_right(starts, t) - 1       # the chunks starting at or before t, latest first
        while i >= 0 and reach[i] >= t:              # stop where no earlier chunk reaches t
            if spans[i][1] >= t:
                need.add(i)
                hit = True
            i -= 1
        if not hit:
            loose.append((t, t))
    out: list[list[int]] = []
    for a, b in sorted([spans[i] for i in need] + loose):
        if out and a <= out[-1][1] + 1:          # overlapping or back to back: one window
            out[-1][1] = max(out[-1][1], b)
        else:
            out.append([a, b])
    return [(a, b) for a, b in out]


def iter_frames(files: list[str], wanted: dict[tuple[str, int], object], log_ns, keep_encoded=frozenset()):
    """Decode the wanted (topic, header stamp) messages, logged at the given log times, of the given files; only the
    MCAP chunks holding one of those log times are decompressed, each once (:func:`windows`), and the images are
    decoded from the chunk's bytes where they lie (:mod:`.mcapscan`, :func:`decode_cdr`); a file without a chunk
    index goes through mcap's reader. A CompressedImage of a topic in ``keep_encoded`` comes as its
    :class:`Encoded` file, not decoded (when :func:`encoded` knows it)."""
    topics = sorted({t for t, _ in wanted})
    for f in files:
        with open(f, "rb") as fh:
            reader = mcap_reader(fh, f)
            summary = reader.get_summary()
            if not mcapscan.has_chunk_index(summary):
                yield from _iter_frames_mcap(reader, f, topics, wanted, log_ns, keep_encoded)
                continue
            spans = [(c.message_start_time, c.message_end_time) for c in summary.chunk_indexes]
            wins = windows(log_ns, spans)
            starts = [a for a, _ in wins]
            ids = {cid: c.topic for cid, c in summary.channels.items() if c.topic in topics}
            # the chunks a window reaches into, as mcap's reader reads them for a time range
            chunks = [c for c in summary.chunk_indexes if set(ids) & set(c.message_index_offsets) and
                      _overlaps(wins, starts, c.message_start_time, c.message_end_time)]
            for cid, log_time, data in mcapscan.iter_messages(fh, summary, ids, log_time_order=False, chunks=chunks):
                i = bisect.bisect_right(starts, log_time) - 1
                if i < 0 or log_time > wins[i][1]:          # outside every window: not read by a time range
                    continue
                key = (ids[cid], header_stamp(data))
                if key in wanted:
                    schema = summary.schemas[summary.channels[cid].schema_id].name
                    enc = None
                    if key[0] in keep_encoded and schema.endswith("CompressedImage"):
                        fmt, offset, n = compressed_fields(data)
                        enc = encoded(data[offset:offset + n], fmt)
                    yield wanted[key], key[1], enc or decode_cdr(schema, data)


def _overlaps(wins, starts, a: int, b: int) -> bool:
    """Whether the span [a, b] meets one of the sorted, disjoint windows."""
    i = bisect.bisect_right(starts, b) - 1          # the last window starting at or before b
    return i >= 0 and wins[i][1] >= a


def _iter_frames_mcap(reader, f, topics, wanted, log_ns, keep_encoded=frozenset()):
    """:func:`iter_frames` of one file through mcap's reader and mcap_ros2's decoder (no chunk index)."""
    from mcap_ros2.decoder import DecoderFactory
    factory, decoders = DecoderFactory(), {}
    summary = reader.get_summary()
    spans = [(c.message_start_time, c.message_end_time) for c in (summary.chunk_indexes if summary else [])]
    for lo_ns, hi_ns in windows(log_ns, spans):
        try:    # mcap >= 1.3 names the window bounds; older releases take start_time / end_time
            messages = reader.iter_messages(topics=topics, starting_at=lo_ns, ending_at=hi_ns,
                                            log_time_order=False)
        except TypeError:
            messages = reader.iter_messages(topics=topics, start_time=lo_ns, end_time=hi_ns + 1,
                                            log_time_order=False)
        for schema, channel, msg in messages:
            key = (channel.topic, header_stamp(msg.data))
            if key not in wanted:
                continue
            dec = decoders.get((f, schema.id))
            if dec is None:
                dec = decoders[(f, schema.id)] = factory.decoder_for("cdr", schema)
            decoded = dec(msg.data)
            enc = (encoded(bytes(decoded.data), decoded.format)
                   if channel.topic in keep_encoded and schema.name.endswith("CompressedImage") else None)
            yield wanted[key], key[1], enc or decode_image(schema.name, decoded)


def probe_sizes(rec: Recording) -> dict[str, tuple[int, int]]:
    """(width, height) of the first message of each image stream."""
    out = {}
    for s in IMAGE_STREAMS:
        if not rec.has(s):          # no depth topic: depth from the stereo pair
            continue
        st = rec.streams[s]
        i = int(np.argmin(st.log_ns))
        wanted = {(st.topic, int(st.stamp_ns[i])): s}
        for _, _, img in iter_frames([str(rec.files[st.file_index[i]])], wanted, [int(st.log_ns[i])]):
            out[s] = (img.shape[1], img.shape[0])
            break
    return out
