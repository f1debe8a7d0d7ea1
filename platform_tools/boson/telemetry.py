"""Decode (and, for the simulated rig, encode) the Boson's telemetry line.

With telemetry enabled (telemetrySetState ENABLED) the Boson's UVC Y16 frame grows by telemetry rows:
640x512 becomes 640x514 (``on_device.thermal_telemetry_rows``). This rig expects them *below* the
image (telemetrySetLocation BOTTOM), which is where the export strips them; pass ``location="top"``
for a camera left at the factory default TOP.

Layout (byte offsets in the telemetry line, i.e. the bytes of the first telemetry row as they
arrive in the frame buffer / the ``data`` of the sensor_msgs/Image):

======================  ======  =====  =========================================================
field                   offset  bytes  source
======================  ======  =====  =========================================================
status word             76      8      Elphel Boson640Telemetry.java (STATUS_OFFSET, read as a long)
frame counter           84      4      Elphel Boson640Telemetry.java (FRAME_OFFSET)
frame count at last FFC 88      4      Elphel Boson640Telemetry.java (FRAME_FFC_OFFSET)
======================  ======  =====  =========================================================

**Verify on hardware** (none of this has been checked against a camera yet):

- *Byte order*: multi-byte fields are read big-endian over the line's bytes, the Boson's convention
  for its serial protocol (docs/boson.md); the Elphel reader uses a Java ByteBuffer, big-endian by
  default. The Y16 *pixels* are little-endian (mono16, ``is_bigendian`` 0): if the fields come out
  byte-swapped within 16-bit words on a real camera, set :data:`WORD_SWAPPED`.
- *FFC state in the status word*: no public source read here gives its bit position. Assumed: bits
  4-5 of the status word (its least significant byte), with the values of bosonGetFfcStatus (0 none,
  1 imminent, 2 in progress, 3 complete). This is where FLIR's Lepton telemetry keeps its FFC state,
  with the same four values. :data:`FFC_SHIFT` / :data:`FFC_MASK` hold the assumption.
- *Frames since the last FFC*: frame counter - frame count at last FFC, modulo 2**32.

Pure functions on bytes and numpy arrays: no ROS, no I/O.
"""
from __future__ import annotations

import struct
from dataclasses import dataclass

import numpy as np

from platform_tools.boson.commands import FfcStatus

# ---------------------------------------------------------------- layout (verify on hardware)
#: byte offset of the 8-byte status word (Elphel Boson640Telemetry.java STATUS_OFFSET)
STATUS_OFFSET = 76
STATUS_BYTES = 8
#: byte offset of the u32 frame counter (Elphel FRAME_OFFSET)
FRAME_COUNTER_OFFSET = 84
#: byte offset of the u32 frame count at the last FFC (Elphel FRAME_FFC_OFFSET)
FFC_FRAME_OFFSET = 88
#: the FFC state inside the status word: (status >> FFC_SHIFT) & FFC_MASK (assumed, see above)
FFC_SHIFT = 4
FFC_MASK = 0x3
#: multi-byte fields are big-endian over the line's bytes (assumed, see above)
BYTE_ORDER = ">"
#: True when a camera turns out to deliver the line with each 16-bit word byte-swapped
WORD_SWAPPED = False
#: the line must hold at least this many bytes
MIN_LINE_BYTES = FFC_FRAME_OFFSET + 4

_U64 = struct.Struct(BYTE_ORDER + "Q")
_U32 = struct.Struct(BYTE_ORDER + "I")
LOCATIONS = ("bottom", "top")
#: where this rig keeps the telemetry rows: boson-config sets it (telemetrySetLocation) when it enables them
EXPECTED_LOCATION = "bottom"


class TelemetryError(ValueError):
    """Bytes that cannot be a telemetry line (too short, wrong shape); ``str()`` is one line."""


@dataclass(frozen=True)
class Telemetry:
    frame_counter: int
    ffc_status: FfcStatus
    ffc_frame: int             # frame counter value at the last FFC
    status_word: int

    @property
    def frames_since_ffc(self) -> int:
        return (self.frame_counter - self.ffc_frame) % (1 << 32)

    @property
    def ffc_in_progress(self) -> bool:
        return self.ffc_status == FfcStatus.IN_PROGRESS


def _swap_words(buf: bytes) -> bytes:
    a = np.frombuffer(buf[: len(buf) // 2 * 2], dtype=np.uint16)
    return a.byteswap().tobytes() + buf[len(buf) // 2 * 2:]


def decode_line(line: bytes | bytearray | memoryview | np.ndarray) -> Telemetry:
    """Decode a telemetry line (bytes, or a uint8/uint16 array of the row as it sits in the frame)."""
    if isinstance(line, np.ndarray):
        line = np.ascontiguousarray(line).tobytes()
    buf = bytes(line)
    if len(buf) < MIN_LINE_BYTES:
        raise TelemetryError(f"telemetry line of {len(buf)} bytes; at least {MIN_LINE_BYTES} needed")
    if WORD_SWAPPED:
        buf = _swap_words(buf)
    status = _U64.unpack_from(buf, STATUS_OFFSET)[0]
    return Telemetry(frame_counter=_U32.unpack_from(buf, FRAME_COUNTER_OFFSET)[0],
                     ffc_status=FfcStatus((status >> FFC_SHIFT) & FFC_MASK),
                     ffc_frame=_U32.unpack_from(buf, FFC_FRAME_OFFSET)[0],
                     status_word=status)


def encode_line(frame_counter: int, ffc_status: int, ffc_frame: int, nbytes: int, *,
                status_word: int = 0) -> bytes:
    """A telemetry line of ``nbytes`` bytes holding these values (the simulator's camera); other bytes 0.

    ``status_word`` supplies the status bits other than the FFC state (kept as given)."""
    if nbytes < MIN_LINE_BYTES:
        raise TelemetryError(f"telemetry line of {nbytes} bytes; at least {MIN_LINE_BYTES} needed")
    state = int(FfcStatus(ffc_status))
    buf = bytearray(nbytes)
    word = (int(status_word) & ~(FFC_MASK << FFC_SHIFT) & ((1 << 64) - 1)) | (state << FFC_SHIFT)
    _U64.pack_into(buf, STATUS_OFFSET, word)
    _U32.pack_into(buf, FRAME_COUNTER_OFFSET, int(frame_counter) % (1 << 32))
    _U32.pack_into(buf, FFC_FRAME_OFFSET, int(ffc_frame) % (1 << 32))
    out = bytes(buf)
    return _swap_words(out) if WORD_SWAPPED else out


def _check(rows: int, location: str) -> None:
    if rows < 1:
        raise TelemetryError(f"{rows} telemetry rows: the frame carries no telemetry")
    if location not in LOCATIONS:
        raise TelemetryError(f"telemetry location {location!r}: expected one of {', '.join(LOCATIONS)}")


def split_frame(frame: np.ndarray, rows: int, location: str = EXPECTED_LOCATION) -> tuple[np.ndarray, bytes]:
    """(image rows, telemetry line bytes) of a Y16 frame (H x W uint16) with ``rows`` telemetry rows."""
    _check(rows, location)
    if frame.ndim != 2 or frame.shape[0] <= rows:
        raise TelemetryError(f"a frame of shape {frame.shape} cannot hold {rows} telemetry rows below an image")
    tele = frame[-rows:] if location == "bottom" else frame[:rows]
    image = frame[:-rows] if location == "bottom" else frame[rows:]
    px = np.ascontiguousarray(tele).astype("<u2", copy=False)   # as the bytes of a mono16 frame
    return image, px.tobytes()


def decode_frame(frame: np.ndarray, rows: int, location: str = EXPECTED_LOCATION) -> Telemetry:
    """Telemetry of a Y16 frame given as an array (H x W uint16)."""
    return decode_line(split_frame(frame, rows, location)[1])


def decode_image_data(data: bytes | memoryview, height: int, step: int, rows: int,
                      location: str = EXPECTED_LOCATION) -> Telemetry:
    """Telemetry from the raw ``data`` of a sensor_msgs/Image (mono16), without building an array."""
    _check(rows, location)
    if height <= rows or step <= 0 or len(data) < height * step:
        raise TelemetryError(f"image data of {len(data)} bytes, {height} rows of {step}: "
                             f"no room for {rows} telemetry rows")
    first = (height - rows) * step if location == "bottom" else 0
    return decode_line(bytes(data[first:first + rows * step]))


def write_into(frame: np.ndarray, line: bytes, rows: int, location: str = EXPECTED_LOCATION) -> np.ndarray:
    """A copy of ``frame`` (H x W uint16, telemetry rows included) with ``line`` written into its
    telemetry rows (zero-padded to their size)."""
    _check(rows, location)
    h, w = frame.shape
    size = rows * w * 2
    if len(line) > size:
        raise TelemetryError(f"telemetry line of {len(line)} bytes does not fit {rows} rows of {w} pixels")
    tele = np.frombuffer(line.ljust(size, b"\0"), dtype="<u2").reshape(rows, w)
    out = frame.copy()
    if location == "bottom":
        out[-rows:] = tele
    else:
        out[:rows] = tele
    return out


def telemetry_rows_present(width: int, height: int, model_width: int, model_height: int, rows: int) -> bool:
    """Whether a recorded thermal frame of ``width`` x ``height`` carries ``rows`` telemetry rows below
    an image of the camera model's aspect: its height less the rows is that aspect's height at this
    width (within a pixel: a scaled-down image may have been truncated rather than rounded), and
    nearer to it than the height itself."""
    if rows <= 0 or height <= rows:
        return False
    expected = width * model_height / model_width
    return abs(height - rows - expected) < 1.0 and abs(height - rows - expected) < abs(height - expected)
