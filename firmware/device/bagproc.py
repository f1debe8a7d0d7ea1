"""The recorder process: `ros2 bag record` (or a replacement) started and stopped the safe way.

Stopping sends SIGINT (rosbag2 then closes its files and writes metadata.yaml), waits
``stop_grace_s``; if the process is still there, SIGTERM and ``term_grace_s``; then SIGKILL. Signals
go to the process group, so the `ros2` CLI and the recorder it starts both receive them.
"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol, Sequence


@dataclass(frozen=True)
class BagSpec:
    folder: Path                 # the bag folder; must not exist yet (rosbag2 creates it)
    topics: tuple[str, ...]
    preset: str                  # MCAP storage preset: none, fastwrite, zstd_fast, zstd_small
    split_size_bytes: int
    split_duration_s: int
    cache_bytes: int


class Backend(Protocol):
    name: str

    def argv(self, spec: BagSpec) -> list[str]: ...


class Ros2BagBackend:
    """The real recorder: ros2 bag record -s mcap, split by size and duration."""
    name = "ros2"

    def argv(self, spec: BagSpec) -> list[str]:
        argv = ["ros2", "bag", "record", "-s", "mcap", "-o", str(spec.folder),
                "-b", str(spec.split_size_bytes), "-d", str(spec.split_duration_s),
                "--max-cache-size", str(spec.cache_bytes)]
        if spec.preset != "none":
            argv += ["--storage-preset-profile", spec.preset]
        return argv + list(spec.topics)


@dataclass
class FakeBackend:
    """platform_tools.sim.fake_recorder, misbehaving on request (see its docstring)."""
    misbehave: str = "none"
    extra: Sequence[str] = ()
    name: str = "fake"

    def argv(self, spec: BagSpec) -> list[str]:
        return [sys.executable, "-m", "platform_tools.sim.fake_recorder", "-o", str(spec.folder),
                "--max-bag-size", str(spec.split_size_bytes), "--misbehave", self.misbehave,
                *self.extra, *spec.topics]


def backend_from_spec(spec: str) -> Backend:
    """``ros2``, ``fake`` or ``fake:MODE`` (the --recorder option of record-service)."""
    if spec == "ros2":
        return Ros2BagBackend()
    if spec == "fake" or spec.startswith("fake:"):
        return FakeBackend(spec.partition(":")[2] or "none")
    raise ValueError(f"--recorder {spec}: expected 'ros2', 'fake' or 'fake:MODE'")


@dataclass
class StopResult:
    returncode: int | None
    signals: list[str] = field(default_factory=list)
    seconds: float = 0.0

    @property
    def clean(self) -> bool:
        return self.signals == ["SIGINT"] and self.returncode == 0

    def to_dict(self) -> dict:
        return {"returncode": self.returncode, "signals": self.signals, "seconds": round(self.seconds, 3),
                "clean": self.clean}


class RecorderProcess:
    def __init__(self, argv: list[str], log_path: Path):
        self.argv = argv
        self.log_path = log_path
        self._log = open(log_path, "ab")
        try:
            self.proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=self._log, stderr=subprocess.STDOUT,
                                         start_new_session=True)
        except OSError:
            self._log.close()
            raise
        self.pid = self.proc.pid

    def poll(self) -> int | None:
        return self.proc.poll()

    def _signal(self, sig: signal.Signals) -> None:
        try:
            os.killpg(self.pid, sig)
        except ProcessLookupError:
            pass

    def _wait(self, timeout: float) -> bool:
        try:
            self.proc.wait(timeout=timeout)
            return True
        except subprocess.TimeoutExpired:
            return False

    def stop(self, stop_grace_s: float, term_grace_s: float) -> StopResult:
        t0 = time.monotonic()
        result = StopResult(self.proc.poll())
        if result.returncode is None:
            for sig, wait in ((signal.SIGINT, stop_grace_s), (signal.SIGTERM, term_grace_s), (signal.SIGKILL, 10.0)):
                self._signal(sig)
                result.signals.append(sig.name)
                if self._wait(wait):
                    break
            result.returncode = self.proc.poll()
        self._signal(signal.SIGKILL)     # anything the recorder left behind in its group
        self._log.close()
        result.seconds = time.monotonic() - t0
        return result
