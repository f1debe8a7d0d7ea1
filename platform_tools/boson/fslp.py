"""FSLP, the FLIR Serial Line Protocol, on bytes only (no port is ever touched here).

A frame is ``START | escape(body) | END`` where the body is
``channel (u8) | sequence (u32) | function id (u32) | status (u32) | payload | CRC (u16)``, all
big-endian. The CRC is CRC-16/AUG-CCITT (poly 0x1021, init 0x1D0F) over the unescaped body from the
channel byte to the last payload byte; escaping covers every body byte, the CRC included.
Source: shared/reference/boson-protocol.md.
"""
from __future__ import annotations

import binascii
import struct
from dataclasses import dataclass

START = 0x8E
END = 0xAE
ESC = 0x9E
ESC_OFFSET = 0x0D            # escaped byte = original - 0x0D; decoded = next byte + 0x0D
SPECIAL = frozenset((START, END, ESC))

CHANNEL_COMMAND = 0x00
STATUS_REQUEST = 0xFFFFFFFF
CRC_INIT = 0x1D0F

_HEADER = struct.Struct(">BIII")
HEADER_SIZE = _HEADER.size   # 13
CRC_SIZE = 2
MAX_BODY = 2048              # bytes of an unescaped body, CRC included: the one limit of encoder and decoder


class FslpError(Exception):
    """Bytes that are not a valid FSLP frame. The decoder raises only subclasses of this."""


class FramingError(FslpError):
    """Missing start/end byte, a bad escape sequence, or a frame too short or too long."""


class CrcError(FslpError):
    """The frame's CRC does not match its body."""

    def __init__(self, message: str, expected: int, got: int):
        super().__init__(message)
        self.expected = expected
        self.got = got


@dataclass(frozen=True)
class Frame:
    channel: int
    sequence: int
    function_id: int
    status: int
    payload: bytes = b""

    @property
    def is_request(self) -> bool:
        return self.status == STATUS_REQUEST


def crc16(data: bytes) -> int:
    """CRC-16/AUG-CCITT: binascii.crc_hqx is CRC-CCITT with poly 0x1021, no reflection, no xor."""
    return binascii.crc_hqx(bytes(data), CRC_INIT)


def escape(body: bytes) -> bytes:
    out = bytearray()
    for b in body:
        if b in SPECIAL:
            out.append(ESC)
            out.append(b - ESC_OFFSET)
        else:
            out.append(b)
    return bytes(out)


def unescape(data: bytes) -> bytes:
    out = bytearray()
    it = iter(data)
    for b in it:
        if b == ESC:
            nxt = next(it, None)
            if nxt is None:
                raise FramingError("escape byte 0x9E at the end of a frame")
            value = nxt + ESC_OFFSET
            if value not in SPECIAL:
                raise FramingError(f"bad escape sequence 9E {nxt:02X}")
            out.append(value)
        elif b in (START, END):
            raise FramingError(f"unescaped 0x{b:02X} inside a frame body")
        else:
            out.append(b)
    return bytes(out)


def _check_u32(name: str, value: int) -> None:
    if not 0 <= value <= 0xFFFFFFFF:
        raise ValueError(f"{name} {value} does not fit in 32 bits")


def encode_body(frame: Frame, *, crc: int | None = None) -> bytes:
    """The unescaped body with its CRC (``crc`` overrides the computed one: only for fault injection)."""
    if not 0 <= frame.channel <= 0xFF:
        raise ValueError(f"channel {frame.channel} does not fit in a byte")
    for name in ("sequence", "function_id", "status"):
        _check_u32(name, getattr(frame, name))
    data = _HEADER.pack(frame.channel, frame.sequence, frame.function_id, frame.status) + bytes(frame.payload)
    if len(data) + CRC_SIZE > MAX_BODY:
        raise ValueError(f"payload of {len(frame.payload)} bytes is too long for one frame")
    return data + (crc16(data) if crc is None else crc).to_bytes(2, "big")


def encode(frame: Frame, *, crc: int | None = None) -> bytes:
    return bytes((START,)) + escape(encode_body(frame, crc=crc)) + bytes((END,))


def request(sequence: int, function_id: int, payload: bytes = b"", channel: int = CHANNEL_COMMAND) -> bytes:
    """The bytes of a command request (status 0xFFFFFFFF)."""
    return encode(Frame(channel, sequence, function_id, STATUS_REQUEST, payload))


def reply(req: Frame, status: int, payload: bytes = b"") -> Frame:
    """The reply frame to a request: same channel, sequence and function id."""
    return Frame(req.channel, req.sequence, req.function_id, status, payload)


def decode_body(body: bytes) -> Frame:
    if len(body) > MAX_BODY:
        raise FramingError(f"frame body of {len(body)} bytes is longer than the {MAX_BODY}-byte limit")
    if len(body) < HEADER_SIZE + CRC_SIZE:
        raise FramingError(f"frame body of {len(body)} bytes is shorter than the "
                           f"{HEADER_SIZE + CRC_SIZE}-byte minimum")
    data, got = body[:-CRC_SIZE], int.from_bytes(body[-CRC_SIZE:], "big")
    expected = crc16(data)
    if got != expected:
        raise CrcError(f"CRC mismatch: frame says {got:04X}, body gives {expected:04X}", expected, got)
    channel, seq, fid, status = _HEADER.unpack_from(data)
    return Frame(channel, seq, fid, status, bytes(data[HEADER_SIZE:]))


def decode(raw: bytes) -> Frame:
    """One complete frame, START to END inclusive."""
    raw = bytes(raw)
    if len(raw) < 2 or raw[0] != START or raw[-1] != END:
        raise FramingError("a frame must start with 0x8E and end with 0xAE")
    inner = raw[1:-1]
    if len(inner) > 2 * MAX_BODY:
        raise FramingError(f"frame of {len(raw)} bytes is longer than any FSLP frame")
    return decode_body(unescape(inner))


class StreamDecoder:
    """Cut a byte stream into frames. ``feed`` never raises: it returns decoded frames and, in order,
    the :class:`FslpError` of every malformed one. Bytes outside a frame are counted as noise; a
    START inside a frame abandons the unfinished one (a dropped END) and starts afresh."""

    def __init__(self) -> None:
        self._buf = bytearray()
        self._in_frame = False
        self.noise_bytes = 0

    def reset(self) -> None:
        self._buf.clear()
        self._in_frame = False

    def feed(self, data: bytes) -> list[Frame | FslpError]:
        out: list[Frame | FslpError] = []
        for b in data:
            if b == START:
                if self._in_frame and self._buf:
                    out.append(FramingError(f"frame abandoned after {len(self._buf)} bytes (no end byte)"))
                self._buf.clear()
                self._in_frame = True
            elif not self._in_frame:
                self.noise_bytes += 1
            elif b == END:
                try:
                    out.append(decode_body(unescape(self._buf)))
                except FslpError as exc:
                    out.append(exc)
                self._buf.clear()
                self._in_frame = False
            else:
                self._buf.append(b)
                if len(self._buf) > 2 * MAX_BODY:
                    out.append(FramingError("frame longer than any FSLP frame; resynchronising"))
                    self._buf.clear()
                    self._in_frame = False
        return out


def has_special_byte(value: int) -> bool:
    return any(b in SPECIAL for b in value.to_bytes(4, "big"))


def next_sequence(seq: int) -> int:
    """The sequence number after ``seq``: increments (wrapping past 0xFFFFFFFF to 1) and skips
    values whose bytes contain 0x8E, 0x9E or 0xAE, as FLIR's SDK does."""
    n = seq
    while True:
        n = (n + 1) & 0xFFFFFFFF
        if n != 0 and not has_special_byte(n):
            return n
