"""Where recordings land: the mount point of a path, its free space, the disk watchdog, and flushing a
finished recording to the drive before the LED says the power may be cut."""
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


def sync_tree(folder: Path) -> int:
    """fsync every file and folder under `folder` (and `folder` itself), so that what the page cache
    holds is on the drive: after this a power cut loses nothing of the recording. Returns the count."""
    n = 0
    for root, _dirs, files in os.walk(folder, topdown=False):
        for name in files:
            path = os.path.join(root, name)
            if os.path.islink(path):
                continue
            fd = os.open(path, os.O_RDONLY)
            try:
                os.fsync(fd)
            finally:
                os.close(fd)
            n += 1
        fd = os.open(root, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
        n += 1
    return n


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
