"""The recorder state machine, driven by the record button.

    IDLE --press--> (pre-flight) --> RECORDING --press / disk low--> STOPPING --> IDLE
      |                  \\-- failed --> ERROR (LED blinks the code)      |
      |                                    recorder died --> ERROR   (file damaged --> ERROR)
    ERROR --press--> try again, like IDLE;  long press anywhere: stop if recording, else run the
    pre-flight and show its result (three quick blinks: all good). It never deletes anything.

Stopping runs in a worker thread (the LED keeps blinking, the button is ignored meanwhile): SIGINT,
wait, SIGTERM, wait, SIGKILL; then every MCAP is checked and, when its summary is missing, a
recovered copy is written next to it; then recording.json is completed. At start-up, recordings
left with status ``recording`` (power loss, a killed service) get the same treatment.

Every fault goes to the log, to the recording's metadata, and to ``events.jsonl`` in the output folder.
"""
from __future__ import annotations

import enum
import json
import logging
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from platform_tools.rig import Rig
from firmware.device import led, mcapcheck, metadata
from firmware.device.bagproc import Backend, BagSpec, RecorderProcess, StopResult
from firmware.device.button import Button, Press
from firmware.device.gpio import Gpio
from firmware.device.preflight import Report
from firmware.device.storage import GB, DiskWatchdog, sync_tree
from firmware.device.topics import recorded_topics

log = logging.getLogger("platform_tools.recorder")

BAG_DIR = "bag"
CHECK_OK_SHOW_S = 3.0


class State(enum.Enum):
    IDLE = "idle"
    RECORDING = "recording"
    STOPPING = "stopping"
    ERROR = "error"


@dataclass
class Session:
    name: str
    folder: Path
    meta: dict
    proc: RecorderProcess | None = None
    started: float = field(default_factory=time.monotonic)

    @property
    def bag(self) -> Path:
        return self.folder / BAG_DIR


class Recorder:
    def __init__(self, rig: Rig, backend: Backend, *, output_dir: Path | None = None,
                 preflight: Callable[[], Report], calibration: Path | None = None,
                 clock: Callable[[], float] = time.monotonic):
        self.rig = rig
        self.backend = backend
        self.output_dir = Path(output_dir or rig.desc.recording.output_dir)
        self.preflight = preflight
        self.calibration = calibration
        self.clock = clock
        od = rig.desc.on_device
        self.watchdog = DiskWatchdog(self.output_dir, od.watchdog.stop_free_gb * GB)
        self._lock = threading.RLock()
        self.state = State.IDLE
        self.error_code: led.ErrorCode | None = None
        self.session: Session | None = None
        self._worker: threading.Thread | None = None
        self._show_ok_until = 0.0
        self._next_watch = 0.0
        self.finished: list[dict] = []    # metadata of every recording finished by this service

    # ------------------------------------------------------------------ events
    def event(self, kind: str, **fields) -> None:
        rec = {"t": metadata.utc_now(), "event": kind, "state": self.state.value} | fields
        (log.error if kind.startswith("fault") else log.info)("%s %s", kind, json.dumps(fields, default=str))
        try:
            self.output_dir.mkdir(parents=True, exist_ok=True)
            with open(self.output_dir / "events.jsonl", "a") as f:
                f.write(json.dumps(rec, default=str) + "\n")
        except OSError as exc:   # a full or missing disk must not stop the state machine
            log.error("cannot append to %s: %s", self.output_dir / "events.jsonl", exc)

    def fault(self, code: led.ErrorCode, message: str, **fields) -> None:
        self.event("fault", code=code.name, blinks=int(code), message=message, **fields)
        if self.session is not None:
            self.session.meta["faults"].append({"t": metadata.utc_now(), "code": code.name, "message": message})

    def press(self, kind: Press) -> None:
        with self._lock:
            self.event("press", press=kind.value)
            if self.state is State.STOPPING:
                return
            if self.state is State.RECORDING:
                self.stop_async("button" if kind is Press.SHORT else "long press")
            elif kind is Press.SHORT:
                self.start()
            else:
                self.show_preflight()

    # ------------------------------------------------------------------ start
    def _run_preflight(self) -> Report | None:
        report = self.preflight()
        if not report.ok:
            self._set_error(led.ErrorCode.PREFLIGHT, "pre-flight failed: " +
                            "; ".join(f"{c.name}: {c.detail}" for c in report.failed()))
            return None
        return report

    def show_preflight(self) -> None:
        if self._run_preflight() is not None:
            self.state, self.error_code = State.IDLE, None
            self._show_ok_until = self.clock() + CHECK_OK_SHOW_S
            self.event("preflight ok")

    def _new_name(self) -> str:
        base = time.strftime("%Y%m%d-%H%M%S", time.gmtime())
        name, i = base, 1
        while (self.output_dir / name).exists():
            i += 1
            name = f"{base}-{i}"
        return name

    def _bag_spec(self, folder: Path) -> BagSpec:
        rec = self.rig.desc.recording
        return BagSpec(folder / BAG_DIR, recorded_topics(self.rig),
                       rec.compression_preset, int(rec.split_size_gb * 1e9), int(rec.split_duration_s),
                       rec.cache_mb * 1024 * 1024)

    def start(self) -> bool:
        with self._lock:
            report = self._run_preflight()
            if report is None:
                return False
            name = self._new_name()
            folder = self.output_dir / name
            spec = self._bag_spec(folder)
            argv = self.backend.argv(spec)
            try:
                folder.mkdir(parents=True)
                meta = metadata.new_metadata(self.rig, name, report.cameras, self.calibration,
                                             {"backend": self.backend.name, "argv": argv})
                metadata.write(folder, meta)
                session = Session(name, folder, meta)
                session.proc = RecorderProcess(argv, folder / "recorder.log")
            except OSError as exc:
                self._set_error(led.ErrorCode.RECORDER_START, f"cannot start the recorder ({argv[0]}): {exc}")
                _remove_empty_session(folder)
                return False
            session.meta["recorder"]["pid"] = session.proc.pid
            metadata.write(folder, session.meta)
            self.session = session
            self.state, self.error_code = State.RECORDING, None
            self._next_watch = self.clock()
            self.event("recording started", name=name, pid=session.proc.pid)
            return True

    # ------------------------------------------------------------------ stop
    def stop_async(self, reason: str, then: State = State.IDLE, code: led.ErrorCode | None = None) -> None:
        with self._lock:
            if self.state is not State.RECORDING:
                return
            self.state = State.STOPPING
            self.event("stopping", reason=reason)
            self._worker = threading.Thread(target=self._stop_worker, args=(reason, then, code),
                                            name="recorder-stop", daemon=True)
            self._worker.start()

    def _stop_worker(self, reason: str, then: State, code: led.ErrorCode | None) -> None:
        session = self.session
        assert session is not None and session.proc is not None
        od = self.rig.desc.on_device
        result = session.proc.stop(self.rig.desc.recording.stop_grace_s, od.recorder_term_grace_s)
        hung = len(result.signals) > 1
        if hung:
            self.fault(led.ErrorCode.RECORDER_HUNG,
                       f"the recorder did not stop on SIGINT within {self.rig.desc.recording.stop_grace_s:g} s; "
                       f"sent {', '.join(result.signals)}", returncode=result.returncode)
        damaged = self.finalize(session, reason, result)
        with self._lock:
            self.session = None
            if damaged:
                self._set_error(led.ErrorCode.FILE_DAMAGED, f"{session.name}: a file could not be recovered")
            elif then is State.ERROR and code is not None:
                self.state, self.error_code = State.ERROR, code
            elif hung:
                self.state, self.error_code = State.ERROR, led.ErrorCode.RECORDER_HUNG
            else:
                self.state, self.error_code = State.IDLE, None
            self.event("recording finished", name=session.name, reason=reason, state_after=self.state.value)

    def finalize(self, session: Session, reason: str, result: StopResult | None) -> bool:
        """Check (and recover) every MCAP, complete the metadata. Returns True when data was lost."""
        damaged = False
        files = []
        for path in sorted(session.bag.glob("*.mcap")) if session.bag.is_dir() else []:
            if mcapcheck.is_recovered_copy(path):
                continue
            status = mcapcheck.check_crcs(path)   # the summary and each chunk's CRC, no message parsed
            entry = {"file": str(path.relative_to(session.folder)), "size_bytes": path.stat().st_size,
                     **{k: v for k, v in status.to_dict().items() if k != "path"}}
            if not status.ok:
                self.fault(led.ErrorCode.FILE_DAMAGED, f"{path.name}: {status.error}; recovering", file=str(path))
                try:
                    rec = mcapcheck.recover(path)
                    entry["recovered"] = rec.to_dict() | {"path": str(Path(rec.path).relative_to(session.folder))}
                    self.event("recovered", file=str(path), messages=rec.messages, damage=rec.stopped_at)
                except OSError as exc:
                    damaged = True
                    self.fault(led.ErrorCode.FILE_DAMAGED, f"{path.name}: recovery failed: {exc}")
            files.append(entry)
        meta = session.meta
        meta["files"] = files
        meta["status"] = "stopped" if result is not None and result.clean else (
            "interrupted" if result is None else "stopped with faults")
        meta["stopped_utc"] = metadata.utc_now()
        meta["duration_s"] = round(time.monotonic() - session.started, 3) if result is not None else None
        meta["stop"] = {"reason": reason} | (result.to_dict() if result is not None else {})
        try:
            metadata.write(session.folder, meta)
        except OSError as exc:
            self.fault(led.ErrorCode.DISK_FULL, f"cannot write {session.folder / metadata.FILE_NAME}: {exc}")
        try:   # on the drive before the LED leaves STOPPING (the power may be cut after that)
            self.event("flushed", name=session.name, entries=sync_tree(session.folder))
        except OSError as exc:
            self.fault(led.ErrorCode.DISK_FULL, f"cannot flush {session.folder} to the drive: {exc}")
        self.finished.append(meta)
        return damaged

    def wait_stopped(self, timeout: float) -> bool:
        w = self._worker
        if w is not None:
            w.join(timeout)
            return not w.is_alive()
        return True

    # ------------------------------------------------------------------ periodic
    def tick(self) -> None:
        with self._lock:
            if self.state is not State.RECORDING or self.session is None:
                return
            rc = self.session.proc.poll()
            if rc is not None:
                self.fault(led.ErrorCode.RECORDER_CRASHED, f"the recorder exited with status {rc} during the recording",
                           returncode=rc, log=str(self.session.folder / "recorder.log"))
                self.stop_async("recorder exited", then=State.ERROR, code=led.ErrorCode.RECORDER_CRASHED)
                return
            now = self.clock()
            if now >= self._next_watch:
                self._next_watch = now + self.rig.desc.on_device.watchdog.check_period_s
                ok, free = self.watchdog.check()
                if not ok:
                    self.fault(led.ErrorCode.DISK_FULL, f"{free / GB:.2f} GB free on the data drive, below "
                               f"on_device.watchdog.stop_free_gb={self.rig.desc.on_device.watchdog.stop_free_gb:g}: "
                               f"stopping", free_bytes=free)
                    self.stop_async("disk nearly full", then=State.ERROR, code=led.ErrorCode.DISK_FULL)

    def shutdown(self, reason: str, timeout: float | None = None) -> None:
        """Stop a running recording cleanly and wait for it (SIGTERM to the service, docker stop)."""
        self.stop_async(reason)
        self.wait_stopped(timeout if timeout is not None else 3600)

    def led_level(self) -> int:
        now = self.clock()
        if self.state is State.IDLE and now < self._show_ok_until:
            return led.level_at("check_ok", now)
        return led.level_at(self.state.value, now, int(self.error_code or 0))

    def _set_error(self, code: led.ErrorCode, message: str) -> None:
        self.fault(code, message)
        self.state, self.error_code = State.ERROR, code

    # ------------------------------------------------------------------ after a power loss
    def recover_interrupted_async(self) -> None:
        """`recover_interrupted` in the worker thread, the LED showing STOPPING (do not cut the power)
        meanwhile; presses are ignored until it is done, then the state is IDLE."""
        with self._lock:
            if self.state is not State.IDLE:
                return
            self.state = State.STOPPING

        def work() -> None:
            try:
                self.recover_interrupted()
            finally:
                with self._lock:
                    self.state = State.IDLE
        self._worker = threading.Thread(target=work, name="recorder-recover", daemon=True)
        self._worker.start()

    def recover_interrupted(self) -> list[str]:
        """Finish recordings a previous run left with status ``recording``."""
        done = []
        if not self.output_dir.is_dir():
            return done
        for meta_path in sorted(self.output_dir.glob(f"*/{metadata.FILE_NAME}")):
            try:
                meta = metadata.read(meta_path.parent)
            except (OSError, ValueError) as exc:
                self.event("fault", code="METADATA", message=f"{meta_path}: unreadable ({exc})")
                continue
            if meta.get("status") != "recording":
                continue
            session = Session(meta["name"], meta_path.parent, meta)
            self.session = session
            self.fault(led.ErrorCode.FILE_DAMAGED, f"{session.name} was not stopped (power loss or a killed "
                                                   f"service): checking its files")
            self.finalize(session, "interrupted: found at start-up", None)
            self.session = None
            done.append(session.name)
        return done


def _remove_empty_session(folder: Path) -> None:
    import shutil
    if folder.is_dir() and not (folder / BAG_DIR).exists():
        shutil.rmtree(folder, ignore_errors=True)


class ButtonLoop:
    """Samples the button, feeds the state machine, drives the LED, until `stop` is set."""

    def __init__(self, recorder: Recorder, gpio: Gpio, button: Button, pin: int, led_pin: int,
                 period_s: float = 0.01):
        self.recorder, self.gpio, self.button = recorder, gpio, button
        self.pin, self.led_pin, self.period_s = pin, led_pin, period_s
        gpio.setup_input(pin)
        gpio.setup_output(led_pin)
        self._led = -1

    def step(self) -> None:
        now = self.recorder.clock()
        for press in self.button.sample(now, self.gpio.read(self.pin)):
            self.recorder.press(press)
        self.recorder.tick()
        level = self.recorder.led_level()
        if level != self._led:
            self.gpio.write(self.led_pin, level)
            self._led = level

    def run(self, stop: threading.Event) -> None:
        while not stop.is_set():
            self.step()
            stop.wait(self.period_s)
        self.gpio.write(self.led_pin, 0)
