"""An in-memory :class:`~platform_tools.boson.transport.Transport`: the client's requests go to a
function that answers on bytes, its answer is what the client reads next. No pty, no thread, no
pyserial: the client's framing, reply matching, retries and re-opening are tested on bytes alone
(the pty emulator stays for end-to-end tests).

    port = LoopbackTransport(answer_with(BosonState(93588)))        # an emulated camera's state
    with BosonClient(port) as client:
        client.call(C.GET_CAMERA_SN)                                  # -> 93588
"""
from __future__ import annotations

import time
from collections import deque
from typing import Callable, Iterable

from .codes import PortGone

#: bytes the client wrote -> the chunks the camera sends back (each read returns one chunk)
Responder = Callable[[bytes], Iterable[bytes]]


class LoopbackTransport:
    """``respond(written)`` is called on every write; the chunks it returns are queued for reading.
    ``written`` keeps every write; :meth:`vanish` makes the port disappear for the next ``n``
    operations (reads and writes raise PortGone, as after a re-enumeration) until it is re-opened."""

    def __init__(self, respond: Responder, path: str = "loopback"):
        self.respond = respond
        self.path = path
        self.reopens = 0
        self.written: list[bytes] = []
        self._pending: deque[bytes] = deque()
        self._open = False
        self._gone = False

    @property
    def is_open(self) -> bool:
        return self._open

    def open(self) -> None:
        self._open, self._gone = True, False
        self._pending.clear()

    def close(self) -> None:
        self._open = False

    def vanish(self) -> None:
        """The port disappears (the camera rebooted): the next read or write raises PortGone."""
        self._gone = True

    def _check(self, what: str) -> None:
        if not self._open or self._gone:
            raise PortGone(f"{self.path}: port lost while {what}")

    def flush_input(self) -> None:
        self._check("flushing")
        self._pending.clear()

    def write(self, data: bytes) -> None:
        self._check("writing")
        self.written.append(bytes(data))
        self._pending.extend(c for c in self.respond(bytes(data)) if c)

    def read(self, timeout_s: float) -> bytes:
        self._check("reading")
        if self._pending:
            return self._pending.popleft()
        time.sleep(max(timeout_s, 0.0))     # nothing will arrive: the camera did not answer
        return b""

    def wait_gone(self, timeout_s: float) -> bool:
        return True

    def reopen(self, timeout_s: float) -> None:
        self.close()
        self.open()
        self.reopens += 1
