"""tests/dataset/pngsame.py, the comparison the stop tests use: two PNGs of one image whose IDAT was deflated
differently (ISA-L's level 1 and zlib's level 9 here, as ISA-L itself sometimes does: pngsame's docstring) hold the
same; a changed pixel, another row filter, a broken file do not."""
from __future__ import annotations

import struct
import zlib

import numpy as np
import pytest

from platform_tools.dataset import encode
from tests.dataset.pngsame import png_content, same_file


def _img() -> np.ndarray:
    rng = np.random.default_rng(3)
    base = np.add.outer(np.arange(77), np.arange(96)).astype(np.uint8)
    return base + rng.integers(0, 6, base.shape, dtype=np.uint8)


def _with_idat(png: bytes, idat: bytes) -> bytes:
    """The same PNG with its IDAT data replaced (one chunk, its CRC recomputed)."""
    others, _ = png_content(png)
    ihdr = others[0][1]

    def chunk(kind: bytes, body: bytes) -> bytes:
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(body, zlib.crc32(kind)))
    return encode.SIGNATURE + chunk(b"IHDR", ihdr) + chunk(b"IDAT", idat) + chunk(b"IEND", b"")


def _pair() -> tuple[bytes, bytes]:
    a = encode.png(_img())
    b = _with_idat(a, zlib.compress(png_content(a)[1], 9))
    return a, b


def test_one_image_deflated_two_ways_differs_in_bytes_and_holds_the_same():
    a, b = _pair()
    assert a != b
    assert same_file("rec/thermal_left/8bit/000111.png", a, b)


def test_one_pixel_changed_is_not_the_same():
    img = _img()
    a = encode.png(img)
    img[10, 20] ^= 1
    assert not same_file("000111.png", a, encode.png(img))


def test_another_row_filter_is_not_the_same_though_the_pixels_are():
    img = _img()
    assert not same_file("000111.png", encode.png(img, filter_type=encode.FILTER_UP),
                         encode.png(img, filter_type=encode.FILTER_SUB))


def test_other_files_compare_byte_for_byte():
    a, b = _pair()
    assert not same_file("index.csv", a, b) and same_file("index.csv", b"x,y\n", b"x,y\n")


@pytest.mark.parametrize("cut", ["signature", "short", "crc", "no_iend"])
def test_a_broken_png_is_refused(cut):
    a, _ = _pair()
    bad = {"signature": b"\x00" + a[1:], "short": a[:-20],
           "crc": a[:41] + bytes([a[41] ^ 0xFF]) + a[42:],          # a byte inside the IDAT's data
           "no_iend": a[:-12]}[cut]
    with pytest.raises(ValueError):
        png_content(bad)
