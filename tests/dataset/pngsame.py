"""Comparing the export's PNG files as what they hold, not as their bytes.

ISA-L's deflate (the export's default PNG writer, platform_tools/dataset/encode.py) does not always give the same
bytes for the same input: in a resumed export under load, about one 8-bit thermal image in a thousand came out with
other Huffman tables (3,627 against 3,628 bytes of IDAT; the first differing byte is the 5th of the zlib stream),
from scanlines identical byte for byte, and a fresh process compressed those scanlines to the reference's bytes.
So a test that two exports wrote the same images compares each PNG's chunks other than IDAT (the header: size,
bit depth, colour type) and its inflated IDAT (the filtered scanlines: the pixels and the filter chosen for each
row), and every other file byte for byte."""
from __future__ import annotations

import struct
import zlib

SIGNATURE = b"\x89PNG\r\n\x1a\n"


def png_content(data: bytes) -> tuple[tuple[tuple[bytes, bytes], ...], bytes]:
    """(the chunks other than IDAT as (type, data), in order; the IDAT data inflated). Raises ValueError on a file
    that is not a whole PNG (no signature, a chunk cut short, a CRC that does not match, no IEND)."""
    if not data.startswith(SIGNATURE):
        raise ValueError("not a PNG: no signature")
    i, others, idat = len(SIGNATURE), [], []
    while i < len(data):
        if i + 8 > len(data):
            raise ValueError(f"chunk header cut short at byte {i}")
        n, kind = struct.unpack(">I4s", data[i:i + 8])
        body = data[i + 8:i + 8 + n]
        crc = data[i + 8 + n:i + 12 + n]
        if len(body) != n or len(crc) != 4 or struct.unpack(">I", crc)[0] != zlib.crc32(body, zlib.crc32(kind)):
            raise ValueError(f"chunk {kind!r} at byte {i}: cut short or a bad CRC")
        (idat if kind == b"IDAT" else others).append(body if kind == b"IDAT" else (kind, body))
        i += 12 + n
    if not others or others[-1][0] != b"IEND":
        raise ValueError("no IEND chunk at the end")
    return tuple(others), zlib.decompress(b"".join(idat))


def same_file(name: str, a: bytes, b: bytes) -> bool:
    """Whether two files of an export hold the same: PNGs by :func:`png_content`, anything else byte for byte."""
    if a == b:
        return True
    return name.endswith(".png") and png_content(a) == png_content(b)
