"""Worker processes that end with their parent: the process pool's initializer and how the pool is stopped.

- A worker asks the kernel to SIGKILL it when its parent dies (Linux ``prctl(PR_SET_PDEATHSIG)``; elsewhere a
  thread that watches the parent pid). Without it, workers orphaned by a SIGKILL of the export kept running for
  over ten minutes.
- A worker ignores SIGINT: Ctrl-C reaches the whole process group, and only the parent acts on it, by stopping
  every worker (:func:`stop`) and keeping the chunks already finished, so the same command resumes.
- What a stopped worker was writing is only ever a temporary file (chunk.tmp_name); export removes those.
"""
from __future__ import annotations

import ctypes
import os
import signal
import sys
import threading
import time

#: linux/prctl.h
PR_SET_PDEATHSIG = 1
#: how often the fallback watch (no prctl) looks at the parent pid
WATCH_PERIOD_S = 1.0


def _set_pdeathsig(sig: int) -> bool:
    """Ask the kernel to send ``sig`` to this process when its parent dies; False where there is no prctl."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        return libc.prctl(PR_SET_PDEATHSIG, int(sig), 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


def _watch_parent(parent_pid: int) -> None:
    while os.getppid() == parent_pid:
        time.sleep(WATCH_PERIOD_S)
    os._exit(1)


def die_with_parent(parent_pid: int) -> None:
    """The pool's initializer, run in each worker: end when ``parent_pid`` ends; leave SIGINT to the parent."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if not _set_pdeathsig(signal.SIGKILL):
        threading.Thread(target=_watch_parent, args=(parent_pid,), daemon=True, name="parent-watch").start()
    if os.getppid() != parent_pid:        # the parent died before the request took effect
        os._exit(1)


def stop(processes) -> list[int]:
    """Terminate the given ``multiprocessing`` processes (SIGTERM, then SIGKILL for any still alive) and reap them;
    returns their pids."""
    processes = list(processes)
    for p in processes:
        if p.is_alive():
            p.terminate()
    for p in processes:
        p.join(5)
        if p.is_alive():
            p.kill()
            p.join()
    return [p.pid for p in processes]
