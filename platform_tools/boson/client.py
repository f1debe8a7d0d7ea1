"""One Boson over one transport (its serial port, or any ``transport.Transport``, such as the in-memory
``loopback.LoopbackTransport``): sequence numbers, reply matching, retries with back-off, reboot.

``call(command, *args)`` sends a request and returns the decoded reply value. A reply must echo the
request's channel, sequence number and function id: the current attempt's, or an earlier attempt's of
the same call (a slow camera's late reply answers the same command); anything else is discarded. No
reply, a corrupt reply, and the transient results CamBusy / NotReady are retried a bounded number of
times with exponential back-off; a port that vanishes mid-command is re-opened (the by-id path follows
the camera) and the command retried.

Noise is not a failure by itself: a malformed frame (noise holding the start byte 0x8E, a bad CRC) is
remembered, and the client keeps reading for ``Timeouts.resync_s`` for a valid reply before it calls
the reply bad. Time adapts to the camera: a reply that arrives after its attempt timed out still answers
the call (taken during the next attempt), and every call waits at least ``Timeouts.adapt`` times the
slowest reply latency seen recently (capped at ``Timeouts.max_first_s``), so a slow camera costs its
latency, not a timeout and a retry per command; a dead one costs (retries + 1) x the timeout, as before.
When a late reply answers a call, the camera still owes the replies to the attempts sent after it (it
works through its requests in order): they are drained before the call returns, so the next command
is not sent behind them, its latency is not mistaken for twice the camera's, and the one timeout the
camera cost is the only one of the session.

``camera_serial()`` asks the camera its serial number once per opening of the port: identity and the
set-up read it from the same open client, and a re-opened port (re-enumeration) is asked again.
"""
from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field
from typing import Any, Callable

from . import commands as C
from . import fslp
from .codes import BadReply, CameraError, PortGone, ReplyTimeout, TransportError, error_for
from .transport import Transport

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Timeouts:
    """Seconds. ``first_s``: to the first reply byte; ``rest_s``: from there to the end of the reply;
    ``slow_s``: first byte of slow commands (flash writes, FFC); ``reopen_s``: for a re-enumerated
    port to come back (older Bosons take about 10 s to boot)."""
    first_s: float = 1.0
    rest_s: float = 2.0
    slow_s: float = 5.0
    reopen_s: float = 15.0
    #: after a malformed frame, how long to keep reading for a valid reply
    resync_s: float = 0.02
    #: a call waits at least this many times the slowest recent reply latency ...
    adapt: float = 2.0
    #: ... and never more than this for a first byte
    max_first_s: float = 8.0

    def first_for(self, cmd: C.Command | None) -> float:
        return self.slow_s if cmd is not None and cmd.speed == C.SLOW else self.first_s


@dataclass
class Stats:
    calls: int = 0
    retries: int = 0
    timeouts: int = 0        # attempts that got no reply within their first-byte timeout
    discarded: int = 0       # well-formed frames that did not match the request
    drained: int = 0         # replies to a call's later attempts, read after a late reply answered it
    bad_frames: int = 0      # CRC or framing errors seen
    reopens: int = 0
    errors: list[str] = field(default_factory=list)


Hook = Callable[[str, bytes], None]   # (direction "tx"/"rx", raw bytes) for session logs


class BosonClient:
    def __init__(self, transport: Transport, *, timeouts: Timeouts = Timeouts(), retries: int = 3,
                 backoff_s: float = 0.02, label: str = "", hook: Hook | None = None, first_sequence: int = 1):
        self.transport = transport
        self.timeouts = timeouts
        self.retries = retries
        self.backoff_s = backoff_s
        self.label = label or transport.path
        self.hook = hook
        self._seq = first_sequence - 1
        self.stats = Stats()
        self._decoder = fslp.StreamDecoder()
        self.latency_s = 0.0      # the slowest reply latency of the recent calls (decays by half per call)
        self._serial: tuple[int, int] | None = None   # (camera serial, self.reopens when it was read)

    # ------------------------------------------------------------------ lifecycle
    def open(self) -> "BosonClient":
        if not self.transport.is_open:
            self.transport.open()
        return self

    def close(self) -> None:
        self.transport.close()

    def __enter__(self) -> "BosonClient":
        return self.open()

    def __exit__(self, *exc) -> None:
        self.close()

    @property
    def reopens(self) -> int:
        return self.stats.reopens

    def next_sequence(self) -> int:
        self._seq = fslp.next_sequence(self._seq)
        return self._seq

    @property
    def requests(self) -> int:
        """Requests sent so far (every attempt of every call)."""
        return self.stats.calls + self.stats.retries

    def camera_serial(self) -> int:
        """The camera's serial number (bosonGetCameraSN), asked once per opening of the port."""
        if self._serial is None or self._serial[1] != self.reopens:
            sn = self.call(C.GET_CAMERA_SN)
            self._serial = (sn, self.reopens)
        return self._serial[0]

    # ------------------------------------------------------------------ one exchange
    def exchange(self, sequence: int, function_id: int, payload: bytes, first_s: float, *,
                 accept: dict[int, float] | None = None, flush: bool = True) -> fslp.Frame:
        """Send one request and wait for its reply (or a late reply to a sequence in ``accept``, which
        maps the earlier attempts' sequence numbers to when they were sent). Raises ReplyTimeout,
        BadReply or PortGone."""
        raw = fslp.request(sequence, function_id, payload)
        if flush:
            self.transport.flush_input()
            self._decoder.reset()
        self.transport.write(raw)
        if self.hook:
            self.hook("tx", raw)
        t0 = time.monotonic()
        sent = dict(accept or {})
        sent[sequence] = t0
        deadline = t0 + first_s
        got_bytes = False
        bad: fslp.FslpError | None = None
        while True:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                if bad is not None:
                    raise BadReply(f"{self.label}: garbled reply to 0x{function_id:08X} ({bad})")
                raise ReplyTimeout(f"{self.label}: no reply to 0x{function_id:08X} within "
                                   f"{time.monotonic() - t0:.2f} s")
            data = self.transport.read(remaining)
            if not data:
                continue
            if self.hook:
                self.hook("rx", data)
            if not got_bytes:
                got_bytes = True
                deadline = max(deadline, time.monotonic() + self.timeouts.rest_s)
            for item in self._decoder.feed(data):
                if isinstance(item, fslp.FslpError):
                    # noise or a corrupt frame: a valid reply may still follow at once (resynchronise)
                    self.stats.bad_frames += 1
                    bad = item
                    deadline = min(deadline, time.monotonic() + self.timeouts.resync_s)
                    continue
                if (item.channel, item.function_id) == (fslp.CHANNEL_COMMAND, function_id) \
                        and item.sequence in sent and not item.is_request:
                    self.latency_s = max(self.latency_s, time.monotonic() - sent[item.sequence])
                    return item
                self.stats.discarded += 1
                log.debug("%s: discarded a frame (seq %d, id 0x%08X) while waiting for seq %d",
                          self.label, item.sequence, item.function_id, sequence)

    # ------------------------------------------------------------------ a command, with retries
    def first_byte_timeout(self, command: C.Command | None) -> float:
        """The configured first-byte timeout, or more for a camera seen to be slow (capped)."""
        base = self.timeouts.first_for(command)
        return min(max(base, self.timeouts.adapt * self.latency_s), max(base, self.timeouts.max_first_s))

    def call_raw(self, function_id: int, payload: bytes = b"", *, command: C.Command | None = None,
                 retries: int | None = None) -> bytes:
        name = command.name if command else f"0x{function_id:08X}"
        retries = self.retries if retries is None else retries
        first_s = self.first_byte_timeout(command)
        self.latency_s /= 2          # decays: a camera that got fast again is not waited for forever
        self.stats.calls += 1
        last: Exception | None = None
        sent: dict[int, float] = {}   # this call's attempts: a late reply to any of them answers it
        flush = True
        for attempt in range(retries + 1):
            if attempt:
                self.stats.retries += 1
                time.sleep(self.backoff_s * (2 ** (attempt - 1)))
            seq = self.next_sequence()
            try:
                frame = self.exchange(seq, function_id, payload, first_s, accept=sent, flush=flush)
            except PortGone as exc:
                last, sent, flush = exc, {}, True
                log.info("%s: port lost during %s; waiting for it to come back", self.label, name)
                self.transport.reopen(self.timeouts.reopen_s)
                self.stats.reopens += 1
                continue
            except ReplyTimeout as exc:
                self.stats.timeouts += 1
                last, flush = exc, False     # keep what arrives late: it may be the reply
                sent[seq] = time.monotonic() - first_s
                # no growth of first_s here: the late reply is taken on the next attempt anyway, and a
                # dead camera must cost (retries + 1) x the timeout, not a geometric series
                log.info("%s: %s (attempt %d of %d)", self.label, exc, attempt + 1, retries + 1)
                continue
            except BadReply as exc:
                last, sent, flush = exc, {}, True
                log.info("%s: %s (attempt %d of %d)", self.label, exc, attempt + 1, retries + 1)
                continue
            if frame.sequence != seq:   # a late reply to an earlier attempt: the later ones are owed
                owed = {s for s, t in sent.items() if t > sent[frame.sequence]} | {seq}
                self._drain(owed, function_id, self.first_byte_timeout(command))   # the latency just learned
            if frame.status == 0:
                return frame.payload
            err = error_for(frame.status, name, self.label)
            if err.transient and attempt < retries:
                last, sent, flush = err, {}, True
                log.info("%s: %s; retrying", self.label, err)
                continue
            raise err
        assert last is not None
        self.stats.errors.append(str(last))
        if isinstance(last, CameraError):
            raise last
        raise type(last)(f"{last} (gave up after {retries + 1} attempts)")

    def _drain(self, sequences: set[int], function_id: int, wait_s: float) -> None:
        """Read the replies the camera still owes to ``sequences`` (a call's attempts sent after the one
        whose late reply answered it), each within ``wait_s``; stop at the first that does not come, or
        when the port vanishes (the next command re-opens it)."""
        while sequences:
            deadline = time.monotonic() + wait_s
            got = False
            while not got and time.monotonic() < deadline:
                try:
                    data = self.transport.read(deadline - time.monotonic())
                except PortGone:
                    return
                if not data:
                    continue
                if self.hook:
                    self.hook("rx", data)
                for item in self._decoder.feed(data):
                    if isinstance(item, fslp.Frame) and item.function_id == function_id \
                            and item.sequence in sequences:
                        sequences.discard(item.sequence)
                        self.stats.drained += 1
                        got = True
            if not got:
                log.info("%s: %d owed repl%s to 0x%08X did not come", self.label, len(sequences),
                         "y" if len(sequences) == 1 else "ies", function_id)
                return

    def call(self, command: C.Command, *args: Any, retries: int | None = None) -> Any:
        payload = command.encode_request(*args)
        reply = self.call_raw(command.function_id, payload, command=command, retries=retries)
        try:
            return command.decode_reply(reply)
        except BadReply as exc:
            raise BadReply(f"{self.label}: {exc}") from None

    # ------------------------------------------------------------------ reboot
    def reboot(self, *, boot_wait_s: float | None = None) -> None:
        """Reboot and wait until the camera answers again on its (re-enumerated) port."""
        raw = fslp.request(self.next_sequence(), C.REBOOT.function_id)
        self.stats.calls += 1
        try:
            self.transport.flush_input()
            self.transport.write(raw)
        except PortGone:
            pass
        if not self.transport.wait_gone(min(3.0, self.timeouts.reopen_s)):
            log.warning("%s: the port did not disappear after the reboot request", self.label)
        self.wait_ready(boot_wait_s)

    def wait_ready(self, timeout_s: float | None = None) -> int:
        """Re-open the port and poll the serial number until the camera answers; returns it."""
        timeout_s = self.timeouts.reopen_s if timeout_s is None else timeout_s
        deadline = time.monotonic() + timeout_s
        self.transport.reopen(timeout_s)
        self.stats.reopens += 1
        while True:
            try:
                sn = self.call(C.GET_CAMERA_SN, retries=0)
                self._serial = (sn, self.reopens)
                return sn
            except (TransportError, CameraError) as exc:
                if isinstance(exc, PortGone):
                    self.transport.reopen(max(deadline - time.monotonic(), 0.0))
                if time.monotonic() > deadline:
                    raise ReplyTimeout(f"{self.label}: the camera did not answer within {timeout_s:g} s "
                                       f"after the reboot ({exc})") from None
                time.sleep(0.05)
