"""An emulated Boson served on a pseudo-terminal, with a by-id link like the real one.

The device thread reads requests from the pty master, answers them from :class:`BosonState`, and
applies fault rules. A reboot closes the pty (the client's port vanishes: reads fail with EIO),
removes the by-id link, waits ``boot_s``, opens a new pty and re-points the link, as a Boson does
when it re-enumerates on USB.
"""
from __future__ import annotations

import json
import os
import random
import select
import threading
import time
import tty
from pathlib import Path
from typing import Callable, TextIO

from .. import commands as C
from .. import fslp
from .faults import FaultRule
from .state import BosonState, error_payload

BUSY, NOT_READY = 0x283, 0x202


def by_id_name(serial: int) -> str:
    return f"usb-FLIR_Boson_{serial}-if00"


class EmulatedBoson:
    def __init__(self, state: BosonState, *, by_id_dir: str | Path | None = None,
                 faults: list[FaultRule] | None = None, boot_s: float = 0.3, seed: int = 0,
                 log: TextIO | None = None, log_lock: threading.Lock | None = None):
        self.state = state
        self.by_id_dir = Path(by_id_dir) if by_id_dir else None
        self.faults: list[FaultRule] = list(faults or [])
        self.boot_s = boot_s
        self.rng = random.Random(seed)
        self._log = log
        self._log_lock = log_lock or threading.Lock()
        self.requests = 0
        self.path: str | None = None
        self._master: int | None = None
        self._slave: int | None = None
        self._stop = threading.Event()
        self._online = threading.Event()
        self._thread: threading.Thread | None = None
        self._decoder = fslp.StreamDecoder()
        self.on_reboot: list[Callable[["EmulatedBoson"], None]] = []

    # ------------------------------------------------------------------ life cycle
    @property
    def serial(self) -> int:
        return self.state.serial

    @property
    def link(self) -> Path | None:
        return self.by_id_dir / by_id_name(self.serial) if self.by_id_dir else None

    @property
    def port(self) -> str:
        """The name a client should use: the by-id link if there is one, else the pty."""
        return str(self.link) if self.link else str(self.path)

    def start(self) -> "EmulatedBoson":
        self._power_on()
        self._thread = threading.Thread(target=self._run, name=f"boson-{self.serial}", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5)
        self._power_off()

    def __enter__(self) -> "EmulatedBoson":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()

    def wait_online(self, timeout_s: float = 5.0) -> bool:
        return self._online.wait(timeout_s)

    def add_fault(self, rule: FaultRule) -> None:
        self.faults.append(rule)

    def clear_faults(self) -> None:
        self.faults.clear()

    def _power_on(self) -> None:
        master, slave = os.openpty()
        tty.setraw(slave)           # no echo, no line editing: bytes pass untouched
        self._master, self._slave = master, slave
        self.path = os.ttyname(slave)
        self._decoder.reset()
        if self.by_id_dir is not None:
            self.by_id_dir.mkdir(parents=True, exist_ok=True)
            tmp = self.by_id_dir / f".{by_id_name(self.serial)}.{os.getpid()}.tmp"
            tmp.unlink(missing_ok=True)
            os.symlink(self.path, tmp)
            os.replace(tmp, self.link)
        self._online.set()
        self._record({"event": "online", "path": self.path})

    def _power_off(self) -> None:
        self._online.clear()
        if self.link is not None:
            try:
                if os.readlink(self.link) == self.path:
                    self.link.unlink()
            except OSError:
                pass
        for fd in (self._master, self._slave):
            if fd is not None:
                try:
                    os.close(fd)
                except OSError:
                    pass
        self._master = self._slave = None

    def reboot(self) -> None:
        """Simulated reboot: the port vanishes, the state reloads from flash, a new port appears."""
        self._record({"event": "reboot"})
        self._power_off()
        if self._stop.wait(self.boot_s):
            return
        self.state.reboot()
        self._power_on()
        for cb in self.on_reboot:
            cb(self)

    # ------------------------------------------------------------------ serving
    def _run(self) -> None:
        while not self._stop.is_set():
            fd = self._master
            if fd is None:
                time.sleep(0.01)
                continue
            try:
                ready, _, _ = select.select([fd], [], [], 0.05)
                if not ready:
                    continue
                data = os.read(fd, 4096)
            except OSError:
                # no client holds the port open (EIO): wait and look again
                time.sleep(0.005)
                continue
            for item in self._decoder.feed(data):
                if isinstance(item, fslp.FslpError):
                    self._record({"event": "bad-request", "error": str(item)})
                    continue
                self._serve(item)

    def _write(self, data: bytes) -> None:
        if self._master is not None:
            try:
                os.write(self._master, data)
            except OSError:
                pass

    def _serve(self, req: fslp.Frame) -> None:
        self.requests += 1
        fired = [r.kind for r in self.faults if r.fires(self.requests, req.function_id, self.rng)]
        cmd = C.BY_ID.get(req.function_id)
        entry = {"dir": "rx", "seq": req.sequence, "fid": f"0x{req.function_id:08X}",
                 "command": cmd.name if cmd else None, "payload": req.payload.hex()}
        if fired:
            entry["faults"] = fired
        self._record(entry)
        if req.channel != fslp.CHANNEL_COMMAND or not req.is_request:
            return
        if "reboot" in fired:
            self.reboot()
            return
        if "delay" in fired:
            delay = max((r.s if r.s is not None else 1.5) for r in self.faults if r.kind == "delay")
            if self._stop.wait(delay):
                return
        if "stall" in fired:
            return
        if "busy" in fired:
            outcome_status, payload, reboot = BUSY, b"", False
        elif "notready" in fired:
            outcome_status, payload, reboot = NOT_READY, b"", False
        elif "ignore" in fired:
            outcome_status, payload, reboot = 0, error_payload(req.function_id), False
        else:
            out = self.state.handle(req.function_id, req.payload)
            outcome_status, payload, reboot = out.status, out.payload, out.reboot
        if outcome_status != 0:
            payload = error_payload(req.function_id)
        rep = fslp.reply(req, outcome_status, payload)
        raw = fslp.encode(rep)
        if "badcrc" in fired:
            raw = fslp.encode(rep, crc=fslp.crc16(fslp.encode_body(rep)[:-2]) ^ 0x5A5A)
        if "drop" in fired:
            i = self.rng.randrange(1, len(raw) - 1)
            raw = raw[:i] + raw[i + 1:]
        if "garbage" in fired:
            noise = bytes(self.rng.choice([b for b in range(256) if b not in fslp.SPECIAL])
                          for _ in range(self.rng.randint(3, 12)))
            raw = noise + raw
        if "wrongseq" in fired:
            stale = fslp.Frame(rep.channel, fslp.next_sequence(rep.sequence + 7), rep.function_id, 0, payload)
            self._write(fslp.encode(stale))
        if "split" in fired:
            cuts = sorted(self.rng.sample(range(1, len(raw)), k=min(3, len(raw) - 1)))
            for a, b in zip([0] + cuts, cuts + [len(raw)]):
                self._write(raw[a:b])
                time.sleep(0.002)
        else:
            self._write(raw)
        self._record({"dir": "tx", "seq": rep.sequence, "fid": f"0x{rep.function_id:08X}",
                      "status": f"0x{rep.status:03X}", "payload": payload.hex()})
        if reboot:
            time.sleep(0.01)   # let the reply drain before the port goes away
            self.reboot()

    # ------------------------------------------------------------------ session log
    def _record(self, entry: dict) -> None:
        if self._log is None:
            return
        line = json.dumps({"t": round(time.time(), 4), "serial": self.serial, **entry})
        with self._log_lock:
            self._log.write(line + "\n")
            self._log.flush()
