"""Whole zstd frames decompressed by the system's libzstd (Debian's ``libzstd1``) through ctypes, python-zstandard
where that library is not found.

Why not python-zstandard alone: its wheels bundle libzstd 1.5.7 built from C only, while Debian 12's libzstd 1.5.4
is built with zstd's x86-64 assembly Huffman decoders. On the thermal chunks of this project's simulated full-size
recording (16-bit frames, ratio 1.95) Debian's library decompresses 1.18-1.25x faster (0.41-0.44 against
0.35-0.36 GB/s, medians of 9 interleaved rounds over 100 and 300 chunks, on this simulator's and on rosbags' copy of
it, AMD EPYC Zen 1; the PyPI ``zstd`` and ``pyzstd`` wheels no faster than python-zstandard). Those chunks are
most of an export's index (docs/dataset.md, "Speed and clean stops"); ``bench/bench_dataset.py --zstd`` measures
both on a recording's own chunks.

The output is the same bytes either way (zstd's format is one); a damaged frame raises :class:`ZstdError` with
libzstd's own error name in both.

:func:`decompress_prefix` decompresses only a frame's first bytes (the export's index: the ZED images' header stamps
before a depth map), by one streaming call into a buffer of that size with a context kept per thread: it replaced a
python-zstandard stream reader per chunk read message by message, 0.22 -> 0.14 s of the 60 s recording's 3.2 s
index (1,793 chunks, cProfile; 2 % of the index's CPU, the same bytes).
"""
from __future__ import annotations

import ctypes
import ctypes.util
import threading

import numpy as np

#: the shared library's names tried in turn (Debian's soname first; find_library runs ldconfig, so it comes second)
_NAMES = ("libzstd.so.1",)

_lib = None          # the loaded library, False once it was looked for and not found
_dctx = threading.local()   # a decompression context per thread, for decompress_prefix (ZSTD_createDCtx)


class _InBuffer(ctypes.Structure):
    """zstd.h ``ZSTD_inBuffer``."""
    _fields_ = [("src", ctypes.c_void_p), ("size", ctypes.c_size_t), ("pos", ctypes.c_size_t)]


class _OutBuffer(ctypes.Structure):
    """zstd.h ``ZSTD_outBuffer``."""
    _fields_ = [("dst", ctypes.c_void_p), ("size", ctypes.c_size_t), ("pos", ctypes.c_size_t)]


#: zstd.h ``ZSTD_ResetDirective``: a new frame, the parameters kept
ZSTD_RESET_SESSION_ONLY = 1


class ZstdError(ValueError):
    """A zstd frame that does not decompress to the size it was said to have (damaged or not zstd); one line."""


def _names():
    yield from _NAMES
    found = ctypes.util.find_library("zstd")
    if found:
        yield found


def _load():
    """The system's libzstd with the functions used here typed, or None."""
    global _lib
    if _lib is None:
        _lib = False
        for name in _names():
            try:
                lib = ctypes.CDLL(name)
                lib.ZSTD_decompress.restype = ctypes.c_size_t
                lib.ZSTD_decompress.argtypes = [ctypes.c_void_p, ctypes.c_size_t, ctypes.c_void_p, ctypes.c_size_t]
                lib.ZSTD_isError.restype = ctypes.c_uint
                lib.ZSTD_isError.argtypes = [ctypes.c_size_t]
                lib.ZSTD_getErrorName.restype = ctypes.c_char_p
                lib.ZSTD_getErrorName.argtypes = [ctypes.c_size_t]
                lib.ZSTD_versionString.restype = ctypes.c_char_p
                lib.ZSTD_createDCtx.restype = ctypes.c_void_p
                lib.ZSTD_createDCtx.argtypes = []
                lib.ZSTD_DCtx_reset.restype = ctypes.c_size_t
                lib.ZSTD_DCtx_reset.argtypes = [ctypes.c_void_p, ctypes.c_int]
                lib.ZSTD_decompressStream.restype = ctypes.c_size_t
                lib.ZSTD_decompressStream.argtypes = [ctypes.c_void_p, ctypes.POINTER(_OutBuffer),
                                                      ctypes.POINTER(_InBuffer)]
            except (OSError, AttributeError):
                continue
            _lib = lib
            break
    return _lib or None


def backend() -> str:
    """Which library :func:`decompress` uses: ``"libzstd 1.5.4 (system)"`` or ``"python-zstandard 1.5.7"``."""
    lib = _load()
    if lib is not None:
        return f"libzstd {lib.ZSTD_versionString().decode()} (system)"
    import zstandard
    return "python-zstandard " + ".".join(map(str, zstandard.ZSTD_VERSION))


def decompress(data, size: int) -> bytes | memoryview:
    """The zstd frame(s) ``data`` (bytes-like, read-only or not), decompressed into ``size`` bytes (a memoryview of
    bytes, or bytes from python-zstandard).

    More than ``size`` bytes of content, or a damaged frame, raise :class:`ZstdError`; fewer give a shorter result
    (the caller compares lengths, as it knows what was expected)."""
    lib = _load()
    if lib is None:
        import zstandard
        try:
            out = zstandard.ZstdDecompressor().decompress(data, max_output_size=size)
        except zstandard.ZstdError as exc:
            raise ZstdError(str(exc)) from None
        if len(out) > size:         # a frame header's content size wins over max_output_size there
            raise ZstdError(f"error decompressing zstd data: {len(out)} bytes of content, more than {size}")
        return out
    src = np.frombuffer(data, np.uint8)
    out = np.empty(size, np.uint8)  # not zeroed: 57 us a chunk saved (a bytearray's memset), all of it written
    got = lib.ZSTD_decompress(out.ctypes.data if size else None, size, src.ctypes.data if src.size else None,
                              src.size)
    if lib.ZSTD_isError(got):
        raise ZstdError(f"error decompressing zstd data: {lib.ZSTD_getErrorName(got).decode()}")
    return memoryview(out)[:got]


def _context(lib):
    """This thread's decompression context (created once, reset before each use; a forked child has its own copy)."""
    ctx = getattr(_dctx, "ctx", None)
    if ctx is None:
        ctx = lib.ZSTD_createDCtx()
        if not ctx:
            raise MemoryError("ZSTD_createDCtx failed")
        _dctx.ctx = ctx
    return ctx


def decompress_prefix(data, n: int) -> bytes | memoryview:
    """The first ``n`` bytes of what the zstd frame(s) ``data`` decompress to, decompressing no further (streaming,
    ``ZSTD_decompressStream`` into a buffer of ``n``): a memoryview, or bytes from python-zstandard. Fewer bytes
    when the content ends before ``n``; a damaged frame raises :class:`ZstdError`. What mcapscan reads of a chunk
    whose wanted messages end early (their header stamps before a depth map): one call instead of one read per
    message, with one context per thread instead of one per chunk."""
    if n <= 0:
        return b""
    lib = _load()
    if lib is None:
        import zstandard
        buf = bytearray(n)
        got = 0
        try:
            reader = zstandard.ZstdDecompressor().stream_reader(data)
            while got < n:
                k = reader.readinto(memoryview(buf)[got:])
                if k == 0:
                    break
                got += k
        except zstandard.ZstdError as exc:
            raise ZstdError(str(exc)) from None
        return memoryview(buf)[:got]
    src = np.frombuffer(data, np.uint8)
    out = np.empty(n, np.uint8)
    ctx = _context(lib)
    r = lib.ZSTD_DCtx_reset(ctx, ZSTD_RESET_SESSION_ONLY)
    if lib.ZSTD_isError(r):
        raise ZstdError(f"error resetting the zstd context: {lib.ZSTD_getErrorName(r).decode()}")
    inb = _InBuffer(src.ctypes.data if src.size else None, src.size, 0)
    outb = _OutBuffer(out.ctypes.data, n, 0)
    while outb.pos < n:
        before = (inb.pos, outb.pos)
        r = lib.ZSTD_decompressStream(ctx, ctypes.byref(outb), ctypes.byref(inb))
        if lib.ZSTD_isError(r):
            raise ZstdError(f"error decompressing zstd data: {lib.ZSTD_getErrorName(r).decode()}")
        if (inb.pos, outb.pos) == before:       # no input left and nothing more to flush: the content ended
            break
    return memoryview(out)[:outb.pos]
