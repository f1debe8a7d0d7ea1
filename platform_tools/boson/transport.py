"""How a client reaches a camera: the :class:`Transport` protocol, and a Boson's serial port through
pyserial (:class:`SerialTransport`): open (exclusive), flush, write, read with a deadline, and re-open
after the camera re-enumerates (reboot, cable pulled and plugged back). An in-memory transport for
tests is platform_tools.boson.loopback.

Use the stable path (``/dev/serial/by-id/usb-FLIR_Boson_<SN>-if00``) where there is one: after a
re-enumeration ``/dev/ttyACM0`` may come back as ``/dev/ttyACM1`` but the by-id link follows it.
"""
from __future__ import annotations

import errno
import logging
import os
import select
import time
from typing import Protocol

import serial

from .codes import PortBusy, PortGone, PortNotFound, PortPermission, TransportError

log = logging.getLogger(__name__)

BAUDRATE = 921600    # USB CDC ignores it; the SDK uses it


def _open_error(path: str, exc: Exception) -> TransportError:
    code = getattr(exc, "errno", None)
    if code is None and isinstance(exc.__context__, OSError):
        code = exc.__context__.errno
    text = str(exc)
    if code == errno.ENOENT or "No such file" in text:
        return PortNotFound(f"{path}: no such port (camera unplugged or not enumerated yet)")
    if code == errno.EACCES or "Permission denied" in text:
        return PortPermission(f"{path}: permission denied; add your user to the 'dialout' group "
                              "(sudo usermod -aG dialout $USER, then log in again)")
    if code in (errno.EBUSY, errno.EAGAIN, errno.EWOULDBLOCK) or "lock" in text.lower():
        return PortBusy(f"{path}: the port is in use by another program; close it and retry")
    return TransportError(f"{path}: cannot open the port ({text})")


class Transport(Protocol):
    """A byte pipe to one camera, as :class:`~platform_tools.boson.client.BosonClient` uses it. Errors
    are the TransportError family of platform_tools.boson.codes: PortGone when the port vanished (the
    client re-opens and retries), PortNotFound / PortPermission / PortBusy when it cannot be opened."""
    path: str            # the name of the port, for messages
    reopens: int         # how many times it was re-opened

    @property
    def is_open(self) -> bool: ...

    def open(self) -> None: ...

    def close(self) -> None: ...

    def flush_input(self) -> None:
        """Drop whatever arrived and was not read yet."""

    def write(self, data: bytes) -> None: ...

    def read(self, timeout_s: float) -> bytes:
        """What has arrived, waiting up to ``timeout_s`` seconds for the first byte; b"" on timeout."""

    def wait_gone(self, timeout_s: float) -> bool:
        """After a reboot request: wait up to ``timeout_s`` seconds until the port disappears; True if it did."""

    def reopen(self, timeout_s: float) -> None:
        """Close, then open again as soon as the port is back, within ``timeout_s`` seconds (else PortGone)."""


class SerialTransport:
    def __init__(self, path: str, *, baudrate: int = BAUDRATE):
        self.path = str(path)
        self.baudrate = baudrate
        self._ser: serial.Serial | None = None
        self.reopens = 0
        self._device = ""          # what the path pointed to when opened (a by-id link is re-pointed)

    # ------------------------------------------------------------------ open / close
    def open(self) -> None:
        try:
            self._ser = serial.Serial(self.path, self.baudrate, timeout=0, write_timeout=2.0, exclusive=True)
            self._device = os.path.realpath(self.path)
        except (serial.SerialException, OSError, ValueError) as exc:
            self.close()
            raise _open_error(self.path, exc) from None
        self.flush_input()

    def close(self) -> None:
        if self._ser is not None:
            try:
                self._ser.close()
            except (serial.SerialException, OSError):
                pass
            self._ser = None

    @property
    def is_open(self) -> bool:
        return self._ser is not None

    def __enter__(self) -> "SerialTransport":
        if not self.is_open:
            self.open()
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _points_elsewhere(self) -> bool:
        """True when the path is gone or names another device node. udev removes the by-id link while we
        look at it, so a link that vanishes between the two system calls counts as gone, not as an error."""
        try:
            return not os.path.exists(self.path) or os.path.realpath(self.path) != self._device
        except OSError:
            return True

    def wait_gone(self, timeout_s: float) -> bool:
        """After a reboot request: wait until the port disappears. True if it did."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if self._points_elsewhere():
                return True
            if self._ser is not None:
                try:
                    self._ser.in_waiting
                    self._ser.read(self._ser.in_waiting or 0)
                except (serial.SerialException, OSError):
                    return True
            time.sleep(0.01)
        return False

    def reopen(self, timeout_s: float) -> None:
        """Close, then open again as soon as the path is back, within ``timeout_s``."""
        self.close()
        deadline = time.monotonic() + timeout_s
        last: Exception | None = None
        delay = 0.01
        while True:
            try:
                self.open()
                self.reopens += 1
                log.info("%s: re-opened", self.path)
                return
            except (PortPermission, PortBusy):
                raise
            except TransportError as exc:
                last = exc
            if time.monotonic() + delay > deadline:
                raise PortGone(f"{self.path}: the camera did not come back within {timeout_s:g} s ({last})")
            time.sleep(delay)
            delay = min(delay * 2, 0.2)

    # ------------------------------------------------------------------ bytes
    def _port(self) -> serial.Serial:
        if self._ser is None:
            raise PortGone(f"{self.path}: port not open")
        return self._ser

    def flush_input(self) -> None:
        try:
            self._port().reset_input_buffer()
        except (serial.SerialException, OSError, TypeError) as exc:
            raise PortGone(f"{self.path}: port lost ({exc})") from None

    def write(self, data: bytes) -> None:
        try:
            self._port().write(data)
        except (serial.SerialException, OSError, TypeError) as exc:
            raise PortGone(f"{self.path}: port lost while writing ({exc})") from None

    def read(self, timeout_s: float) -> bytes:
        """What has arrived, waiting up to ``timeout_s`` for the first byte; b"" on timeout.
        (select + os.read on pyserial's descriptor: changing pyserial's timeout per call would
        re-program the port every time.)"""
        fd = self._port().fileno()
        try:
            ready, _, _ = select.select([fd], [], [], max(timeout_s, 0.0))
            if not ready:
                return b""
            data = os.read(fd, 4096)
        except (OSError, ValueError) as exc:
            raise PortGone(f"{self.path}: port lost while reading ({exc})") from None
        if not data:
            raise PortGone(f"{self.path}: port lost while reading (end of file)")
        return data
