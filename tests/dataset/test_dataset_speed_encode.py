"""The export's PNG writer (platform_tools.dataset.encode): every file it writes is read back, pixel for pixel, by
three readers that share none of its code: libpng (through OpenCV), Pillow, and a decoder written here from the PNG
specification (chunk CRCs checked with Python's zlib, IDAT inflated by zlib, all five filter types undone)."""
from __future__ import annotations

import io
import struct
import zlib

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image

from platform_tools.dataset import encode


def spec_decode(data: bytes) -> np.ndarray:
    """A PNG file (8/16-bit greyscale or truecolour, not interlaced) to an array as cv2.imread gives it (BGR),
    following the PNG specification (W3C, 2nd edition) section by section."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, chunks = 8, []
    while pos < len(data):
        n, = struct.unpack_from(">I", data, pos)
        kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + n]
        crc, = struct.unpack_from(">I", data, pos + 8 + n)
        assert crc == zlib.crc32(kind + body), kind
        chunks.append((kind, body))
        pos += 12 + n
    assert [k for k, _ in chunks][0] == b"IHDR" and chunks[-1] == (b"IEND", b"")
    w, h, depth, colour, comp, filt, interlace = struct.unpack(">IIBBBBB", chunks[0][1])
    assert (comp, filt, interlace) == (0, 0, 0) and depth in (8, 16) and colour in (0, 2)
    channels = 3 if colour == 2 else 1
    bpp = channels * depth // 8
    raw = zlib.decompress(b"".join(b for k, b in chunks if k == b"IDAT"))
    stride = w * bpp
    assert len(raw) == h * (stride + 1)
    out = np.zeros((h, stride), np.int64)
    prev = np.zeros(stride, np.int64)
    for r in range(h):
        ftype, line = raw[r * (stride + 1)], np.frombuffer(raw, np.uint8, stride, r * (stride + 1) + 1).astype(np.int64)
        cur = np.zeros(stride, np.int64)
        for i in range(stride):
            a = cur[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            if ftype == 0:
                pred = 0
            elif ftype == 1:
                pred = a
            elif ftype == 2:
                pred = b
            elif ftype == 3:
                pred = (a + b) // 2
            else:
                assert ftype == 4, ftype
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
            cur[i] = (line[i] + pred) % 256
        out[r], prev = cur, cur
    px = out.astype(np.uint8)
    img = px.view(">u2").astype(np.uint16) if depth == 16 else px
    img = img.reshape(h, w, channels)
    return img[..., 0] if channels == 1 else img[..., ::-1]


@st.composite
def images(draw):
    h, w = draw(st.integers(1, 24)), draw(st.integers(1, 24))
    dtype = draw(st.sampled_from([np.uint8, np.uint16]))
    shape = (h, w) if draw(st.booleans()) else (h, w, 3)
    top = np.iinfo(dtype).max
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    kind = draw(st.sampled_from(["noise", "ramp", "flat", "extremes"]))
    if kind == "noise":
        img = rng.integers(0, top + 1, shape, dtype=np.int64)
    elif kind == "ramp":                      # smooth content, where UP and SUB filters matter
        img = np.add.outer(np.arange(h) * draw(st.integers(0, 300)), np.arange(w) * draw(st.integers(0, 300)))
        img = np.broadcast_to(img[..., None] if len(shape) == 3 else img, shape) + rng.integers(0, 3, shape)
    elif kind == "flat":
        img = np.full(shape, draw(st.integers(0, top)))
    else:                                     # wrap-around of the filters' byte arithmetic
        img = rng.choice([0, 1, top - 1, top], shape)
    return np.clip(img, 0, top).astype(dtype)


@pytest.mark.slow
@settings(max_examples=150, deadline=None)
@given(images(), st.sampled_from(encode.FILTERS), st.sampled_from(list(encode.LEVELS)))
def test_every_written_png_reads_back_as_the_array_by_three_independent_readers(img, filter_type, level):
    data = encode.png(img, level, filter_type)
    assert np.array_equal(cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED).reshape(img.shape), img)
    assert np.array_equal(spec_decode(data), img)
    if img.dtype == np.uint8 or img.ndim == 2:        # Pillow has no 16-bit truecolour mode
        pil = np.asarray(Image.open(io.BytesIO(data)))
        assert np.array_equal(pil.astype(img.dtype).reshape(img.shape), img[..., ::-1] if img.ndim == 3 else img)


def test_scanlines_carry_the_filter_that_was_asked_and_invert_to_the_image():
    img = (np.arange(5 * 7 * 3).reshape(5, 7, 3) * 37 % 256).astype(np.uint8)
    for f in encode.FILTERS:
        lines = encode.scanlines(img, f)
        assert lines.shape == (5, 1 + 7 * 3) and (lines[:, 0] == f).all()
    up = encode.scanlines(img, encode.FILTER_UP)[:, 1:]
    rgb = img[..., ::-1].reshape(5, -1)
    assert np.array_equal(np.cumsum(up, axis=0, dtype=np.uint8), rgb)          # UP undone: sums down the column
    sub = encode.scanlines(img, encode.FILTER_SUB)[:, 1:].reshape(5, 7, 3)
    assert np.array_equal(np.cumsum(sub, axis=1, dtype=np.uint8).reshape(5, -1), rgb)


def test_sixteen_bit_samples_are_big_endian_and_colour_is_rgb():
    img = np.array([[[0x0102, 0x0304, 0x0506]]], np.uint16)          # one BGR pixel
    lines = encode.scanlines(img, encode.FILTER_NONE)
    assert lines.tobytes() == b"\x00\x05\x06\x03\x04\x01\x02"


def test_a_large_image_is_split_into_several_idat_chunks(monkeypatch):
    monkeypatch.setattr(encode, "IDAT_MAX_BYTES", 1000)
    img = np.random.default_rng(3).integers(0, 65536, (64, 80), dtype=np.uint16)
    data = encode.png(img)
    assert data.count(b"IDAT") >= len(data) // 1000 - 1
    assert np.array_equal(spec_decode(data), img)
    assert np.array_equal(cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED), img)


@pytest.mark.parametrize("img, what", [
    (np.zeros((4, 4), np.float32), "float32"),
    (np.zeros((4, 4, 4), np.uint8), "(4, 4, 4)"),
    (np.zeros((4,), np.uint8), "(4,)"),
    (np.zeros((0, 4), np.uint8), "empty"),
])
def test_images_it_cannot_write_are_refused_in_one_line(img, what):
    with pytest.raises(encode.EncodeError, match=what.replace("(", r"\(").replace(")", r"\)")):
        encode.png(img)


@pytest.mark.parametrize("kw, what", [({"level": 4}, "level 4"), ({"filter_type": 4}, "filter 4")])
def test_out_of_range_settings_are_refused(kw, what):
    with pytest.raises(encode.EncodeError, match=what):
        encode.png(np.zeros((2, 2), np.uint8), **kw)
