"""A SIGTERM landing on every line this process's main thread runs inside concurrent.futures while a Pool
(platform_tools.dataset.engines) starts, maps, runs and closes: does the stop still happen, whole?

Run as ``python -m tests.dataset.interrupt_probe [START_METHOD]``; prints JSON lines: how many lines were found,
then one result per cycle. A cycle, then a second one traced, lists the lines (file, function, line number) of
concurrent.futures the main thread runs. Then, for each line, a fresh cycle in which, the first (then, in another
cycle, the second) time the main thread reaches that line, SIGTERM is raised there: its handler (the export
command's: a KeyboardInterrupt) runs at that very line, as a real signal's may. Each cycle reports:
- ``interrupted``: the KeyboardInterrupt came out of the pool's call (a signal is never lost);
- ``manager_alive``: the executor's manager thread still running 10 s after the pool was stopped: the hang
  (it waits on a future's lock the main thread was left holding; at exit the process waits on it forever);
- ``children``: worker processes left running.
The process leaves with os._exit, so that a stuck manager thread cannot hang it: the report says so instead.
"""
from __future__ import annotations

import json
import multiprocessing
import os
import signal
import sys
import threading
import time

from platform_tools.dataset.engines import MANAGER_JOIN_S, Pool

#: the calls of each cycle: a map of this many, then a run of this many tasks
CALLS = 12
#: the times a line is reached at which SIGTERM is raised there, one cycle each: the first, and the second (in a loop
#: that takes the futures' locks one by one, the first time no lock is taken yet; the second, one is)
HITS = (1, 2)


def work(t: int) -> int:
    time.sleep(0.002)
    return t


def scan(a: int) -> int:
    return a * 2


def _terminated(signum, frame):
    raise KeyboardInterrupt         # what platform_tools.cli.export_cmd does with SIGTERM


def _in_futures(frame) -> bool:
    return "concurrent" + os.sep + "futures" + os.sep in frame.f_code.co_filename


def _where(frame) -> tuple[str, str, int]:
    return os.path.basename(frame.f_code.co_filename), frame.f_code.co_name, frame.f_lineno


def cycle(method: str) -> None:
    pool = Pool(2, method=method)
    try:
        assert pool.map(scan, [(a,) for a in range(CALLS)]) == [2 * a for a in range(CALLS)]
        got = []
        pool.run(work, list(range(CALLS)), lambda t, r: got.append(r))
        assert sorted(got) == list(range(CALLS))
    finally:
        pool.close()


def lines_run(method: str) -> dict[tuple[str, str, int], int]:
    """(file, function, line) of concurrent.futures -> how many times the main thread runs it in one cycle."""
    seen: dict[tuple, int] = {}

    def local(frame, event, arg):
        if event == "line":
            where = _where(frame)
            seen[where] = seen.get(where, 0) + 1
        return local

    def tracer(frame, event, arg):
        return local if _in_futures(frame) else None

    cycle(method)           # first: the lines run once per process (concurrent.futures' lazy imports) are run
    sys.settrace(tracer)
    try:
        cycle(method)
    finally:
        sys.settrace(None)
    return seen


def probe(method: str, target: tuple[str, str, int], hit: int) -> dict:
    reached, fired = [], []

    def local(frame, event, arg):
        if event == "line" and not fired and _where(frame) == target:
            reached.append(True)
            if len(reached) == hit:
                fired.append(True)
                sys.settrace(None)
                signal.raise_signal(signal.SIGTERM)     # the handler runs here, before this returns
        return local

    def tracer(frame, event, arg):
        return local if not fired and _in_futures(frame) else None

    before = set(threading.enumerate())
    sys.settrace(tracer)
    interrupted, error = False, None
    try:
        cycle(method)
    except KeyboardInterrupt:
        interrupted = True
    except BaseException as exc:        # noqa: BLE001 - reported: the test names it
        error = f"{type(exc).__name__}: {exc}"
    finally:
        sys.settrace(None)
    managers = [t for t in threading.enumerate() if t not in before and "Manager" in type(t).__name__]
    for t in managers:
        t.join(MANAGER_JOIN_S)
    return {"line": list(target), "hit": hit, "fired": bool(fired), "interrupted": interrupted, "error": error,
            "manager_alive": any(t.is_alive() for t in managers),
            "children": [p.pid for p in multiprocessing.active_children()]}


def main() -> None:
    method = sys.argv[1] if len(sys.argv) > 1 else "fork"
    signal.signal(signal.SIGTERM, _terminated)
    lines = lines_run(method)
    print(json.dumps({"lines": len(lines)}), flush=True)
    for line, n in lines.items():
        for hit in HITS:
            if hit <= n:
                print(json.dumps(probe(method, line, hit)), flush=True)
    os._exit(0)


if __name__ == "__main__":
    main()
