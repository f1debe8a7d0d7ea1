"""Fields of CDR-serialised ROS 2 messages read straight from their bytes (a memoryview of a decompressed chunk is
enough), without decoding the message or copying its pixels: a header stamp, a sensor_msgs/Image's layout, a
sensor_msgs/CompressedImage's format and payload, and the two FFC status types (:func:`bool_message`,
:func:`diagnostic_array`, whole). One parser for the index's chunk scan (:mod:`.indexscan`, run in the export's
workers) and the recording's readers (:mod:`.recording`, :mod:`.decode`).

CDR: a 4-byte encapsulation header (its second byte 1 for little-endian), then the fields, each aligned to its size
counted from the end of that header.
"""
from __future__ import annotations

import struct
from typing import NamedTuple


#: the bytes of a message's CDR data that :func:`header_stamp` reads: the encapsulation header, sec, nanosec
STAMP_BYTES = 12


def header_stamp(data: bytes) -> int:
    """Header stamp (ns) of a CDR-serialised ROS 2 message that starts with std_msgs/Header."""
    endian = "<" if data[1] == 1 else ">"
    sec, nsec = struct.unpack_from(endian + "iI", data, 4)
    return sec * 1_000_000_000 + nsec


def _align(pos: int, n: int) -> int:
    """CDR alignment, counted from the end of the 4-byte encapsulation header."""
    return 4 + ((pos - 4 + n - 1) // n) * n


def _cdr_string(data, pos: int, u32) -> tuple[str, int]:
    """A CDR string at ``pos`` (length with its NUL, bytes): (the text, the position after it); ValueError when the
    data ends before it does."""
    n = u32.unpack_from(data, pos)[0]
    if pos + 4 + n > len(data):
        raise ValueError(f"a CDR string of {n} bytes at byte {pos} of {len(data)}")
    return bytes(data[pos + 4:pos + 4 + n]).rstrip(b"\0").decode("utf-8", "replace"), pos + 4 + n


def image_fields(data, size: int | None = None) -> tuple[int, int, str, bool, int, int]:
    """(height, width, encoding, is_bigendian, step, offset of the pixel bytes) of a CDR-serialised
    sensor_msgs/Image (bytes or a memoryview), read from its fields without copying the pixels. ``size``: the whole
    message's length when ``data`` is only its first bytes (default: ``len(data)``)."""
    endian = "<" if data[1] == 1 else ">"
    u32 = struct.Struct(endian + "I")
    _, pos = _cdr_string(data, 12, u32)                  # after encapsulation, stamp sec + nanosec: frame_id
    pos = _align(pos, 4)
    height, width = struct.unpack_from(endian + "II", data, pos)
    encoding, pos = _cdr_string(data, pos + 8, u32)
    bigendian = bool(data[pos])
    pos = _align(pos + 1, 4)
    step = u32.unpack_from(data, pos)[0]
    pos = _align(pos + 4, 4)
    n = u32.unpack_from(data, pos)[0]
    pos += 4
    if n < height * step or pos + n > (len(data) if size is None else size):
        raise ValueError(f"sensor_msgs/Image of {height} rows x {step} bytes holds {n} bytes")
    return height, width, encoding, bigendian, step, pos


def image_layout(data: bytes, size: int | None = None) -> tuple[int, int, int, int]:
    """(height, width, step, offset of the pixel bytes) of a CDR-serialised sensor_msgs/Image, read
    from its fields without copying the pixels (``size``: as :func:`image_fields`)."""
    height, width, _, _, step, pos = image_fields(data, size)
    return height, width, step, pos


def compressed_fields(data) -> tuple[str, int, int]:
    """(format, offset, length of the compressed bytes) of a CDR-serialised sensor_msgs/CompressedImage."""
    endian = "<" if data[1] == 1 else ">"
    u32 = struct.Struct(endian + "I")
    _, pos = _cdr_string(data, 12, u32)                  # frame_id
    fmt, pos = _cdr_string(data, _align(pos, 4), u32)
    pos = _align(pos, 4)
    n = u32.unpack_from(data, pos)[0]
    if pos + 4 + n > len(data):
        raise ValueError(f"sensor_msgs/CompressedImage of {n} bytes holds {len(data) - pos - 4}")
    return fmt, pos + 4, n


class Time(NamedTuple):
    """builtin_interfaces/msg/Time"""
    sec: int
    nanosec: int


class Header(NamedTuple):
    """std_msgs/msg/Header"""
    stamp: Time
    frame_id: str


class KeyValue(NamedTuple):
    """diagnostic_msgs/msg/KeyValue"""
    key: str
    value: str


class DiagnosticStatus(NamedTuple):
    """diagnostic_msgs/msg/DiagnosticStatus"""
    level: int
    name: str
    message: str
    hardware_id: str
    values: list


class DiagnosticArray(NamedTuple):
    """diagnostic_msgs/msg/DiagnosticArray"""
    header: Header
    status: list


class Bool(NamedTuple):
    """std_msgs/msg/Bool"""
    data: bool


def bool_message(data) -> Bool:
    """A CDR-serialised std_msgs/msg/Bool; ValueError when it holds no byte after the encapsulation header."""
    if len(data) < 5:
        raise ValueError(f"a std_msgs/msg/Bool of {len(data)} bytes")
    return Bool(data[4] != 0)


def diagnostic_array(data) -> DiagnosticArray:
    """A CDR-serialised diagnostic_msgs/msg/DiagnosticArray, whole (the fields mcap_ros2's decoder gives, several
    times faster: an FFC status topic at 30 Hz per camera is a message per frame, each decoded while the index
    scans its chunk, docs/dataset.md "Speed"); ValueError when the data ends before the message does."""
    data = bytes(data)
    try:
        endian = "<" if data[1] == 1 else ">"
        u32 = struct.Struct(endian + "I")
        sec, nanosec = struct.unpack_from(endian + "iI", data, 4)
        frame_id, pos = _cdr_string(data, 12, u32)
        pos = _align(pos, 4)
        count = u32.unpack_from(data, pos)[0]
        pos += 4
        status = []
        for _ in range(count):
            level = data[pos]                                   # an octet: no alignment
            name, pos = _cdr_string(data, _align(pos + 1, 4), u32)
            message, pos = _cdr_string(data, _align(pos, 4), u32)
            hardware_id, pos = _cdr_string(data, _align(pos, 4), u32)
            pos = _align(pos, 4)
            n = u32.unpack_from(data, pos)[0]
            pos += 4
            values = []
            for _ in range(n):
                key, pos = _cdr_string(data, _align(pos, 4), u32)
                value, pos = _cdr_string(data, _align(pos, 4), u32)
                values.append(KeyValue(key, value))
            status.append(DiagnosticStatus(level, name, message, hardware_id, values))
    except (struct.error, IndexError) as exc:
        raise ValueError(f"a diagnostic_msgs/msg/DiagnosticArray cut short ({len(data)} bytes: {exc})") from None
    return DiagnosticArray(Header(Time(sec, nanosec), frame_id), status)
