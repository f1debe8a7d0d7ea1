"""Worker processes that end with their parent: the process pool's initializer and how the pool is stopped.

- A worker asks the kernel to SIGKILL it when its parent dies (Linux ``prctl(PR_SET_PDEATHSIG)``; elsewhere a
  thread that watches the parent pid). Without it, workers orphaned by a SIGKILL of the export kept running for
  over ten minutes.
- A worker ignores SIGINT: Ctrl-C reaches the whole process group, and only the parent acts on it, by stopping
  every worker (:func:`stop`) and keeping the chunks already finished, so the same command resumes.
- What a stopped worker was writing is only ever a temporary file (chunk.tmp_name); export removes those.
- A process that runs chunks keeps the memory it frees for its next allocations (:func:`keep_freed_memory`):
  glibc's malloc otherwise hands every block of a few MB (a decompressed MCAP chunk, an image, a registration's
  accumulators) back to the kernel when it is freed and takes fresh pages for the next one, about 13,000 page
  faults and 20 ms of kernel time per full-size sample (docs/dataset.md "Speed").
"""
from __future__ import annotations

import contextlib
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
#: glibc malloc.h: mallopt parameters
M_TRIM_THRESHOLD, M_MMAP_THRESHOLD = -1, -3
#: blocks up to this size come from the heap, not from their own mmap (32 MiB: glibc's largest allowed value on
#: 64-bit, DEFAULT_MMAP_THRESHOLD_MAX; a registration's largest array is 14 MB)
MMAP_THRESHOLD_BYTES = 32 << 20
#: free memory at the top of the heap kept up to this size instead of being returned to the kernel
TRIM_THRESHOLD_BYTES = 1 << 30
_kept: list[bool] = []


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
    """The pool's initializer, run in each worker: end when ``parent_pid`` ends; leave SIGINT to the parent; die of
    SIGTERM (:func:`stop`) at once, whatever handler a forked worker inherited (the export command turns SIGTERM into
    an interrupt in its own process, which in a worker would only fail the task in hand)."""
    worker_signals()
    if not _set_pdeathsig(signal.SIGKILL):
        threading.Thread(target=_watch_parent, args=(parent_pid,), daemon=True, name="parent-watch").start()
    if os.getppid() != parent_pid:        # the parent died before the request took effect
        os._exit(1)


def worker_signals() -> None:
    """A worker's handlers: SIGINT ignored (the parent acts on Ctrl-C), SIGTERM at its default (ends it at once)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


#: set while :func:`forking_workers` runs: a process forked then is a worker
_forking: list[bool] = []
#: the at-fork hook registered (once per process: a hook cannot be removed)
_hook: list[bool] = []


def _after_fork_in_child() -> None:
    if _forking:
        worker_signals()


@contextlib.contextmanager
def forking_workers():
    """Processes forked in this block (a forking process pool's workers, started by its first submit) take
    :func:`worker_signals` at the fork (``os.register_at_fork``), not later in the pool's initializer: until then a
    worker has this process's handlers, and a SIGTERM from :func:`stop` in that gap ran the export's (a traceback
    in the worker instead of its end). Main thread only; nothing where there is no fork (Windows)."""
    if not _hook and hasattr(os, "register_at_fork"):
        os.register_at_fork(after_in_child=_after_fork_in_child)
        _hook.append(True)
    _forking.append(True)
    try:
        yield
    finally:
        _forking.clear()


def keep_freed_memory() -> bool:
    """Ask glibc's malloc (``mallopt``) to serve blocks up to MMAP_THRESHOLD_BYTES from the heap and to keep up to
    TRIM_THRESHOLD_BYTES of freed heap, so that the large buffers each sample allocates reuse pages already
    mapped. Once per process; a process-wide setting (for the process that runs chunks). False where there is
    no glibc mallopt (the allocator is left as it is)."""
    if _kept:
        return _kept[0]
    ok = False
    if sys.platform.startswith("linux"):
        try:
            libc = ctypes.CDLL(None)
            ok = (libc.mallopt(M_MMAP_THRESHOLD, ctypes.c_int(MMAP_THRESHOLD_BYTES)) == 1
                  and libc.mallopt(M_TRIM_THRESHOLD, ctypes.c_int(TRIM_THRESHOLD_BYTES)) == 1)
        except (OSError, AttributeError):
            ok = False
    _kept.append(ok)
    return ok


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
