"""Where recordings land: the mount point of a path, its free space, and the disk watchdog."""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

GB = 1e9


def existing_ancestor(path: Path) -> Path:
    """The path itself, or its nearest ancestor that exists."""
    path = Path(os.path.abspath(path))
    while not path.exists():
        path = path.parent
    return path


def mount_point(path: Path) -> Path:
    """The mount point of the filesystem `path` (or its nearest existing ancestor) is on."""
    p = existing_ancestor(path)
    while not os.path.ismount(p):
        p = p.parent
    return p


def free_bytes(path: Path) -> int:
    st = os.statvfs(existing_ancestor(path))
    return st.f_bavail * st.f_frsize


@dataclass
class DiskWatchdog:
    """Says stop when the filesystem of `path` has less than `stop_free_bytes` free."""
    path: Path
    stop_free_bytes: float
    lowest_free: int | None = None

    def check(self) -> tuple[bool, int]:
        """(ok, free bytes now)."""
        free = free_bytes(self.path)
        self.lowest_free = free if self.lowest_free is None else min(self.lowest_free, free)
        return free >= self.stop_free_bytes, free
