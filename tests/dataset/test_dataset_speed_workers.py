"""The export's workers start before the work is known (engines.started) and are ready when it comes: numba's kernels
loaded by chunk.warm_up with the argument types of the real call (no second specialisation), mrcal imported with the
standard library's distutils; an exception in the block stops them. Checked in real spawned processes."""
from __future__ import annotations

import json
import multiprocessing
import os
import subprocess
import sys
import time

import pytest

from platform_tools.dataset import engines
from platform_tools.dataset.chunk import warm_up
from tests.conftest import REPO

pytestmark = pytest.mark.slow          # spawned processes that import numba and mrcal


#: the registration's numba kernels an export calls
KERNELS = ("_points_compact", "_splat_packed", "_finish_u8")


def _state(_task=None) -> dict:
    """What a worker holds when its first task starts (run as that task, before anything else)."""
    from platform_tools.dataset import register, thermal8
    return {"pid": os.getpid(), "mcap": "mcap.reader" in sys.modules, "mrcal": "mrcal" in sys.modules,
            "setuptools": "setuptools" in sys.modules,
            "kernels": {n: len(getattr(register, n).signatures) for n in KERNELS}
            | {"_apply": len(thermal8._compiled[0].signatures) if thermal8._compiled else 0},
            "env": os.environ.get("SETUPTOOLS_USE_DISTUTILS")}


def _alive(pid: int) -> bool:
    try:
        return open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def test_started_workers_are_warm_before_their_first_task():
    got = []
    before = os.environ.get("SETUPTOOLS_USE_DISTUTILS")
    children = set(multiprocessing.active_children())
    with engines.started("pool", 2, warm_up) as pool:
        spawned = [p.pid for p in multiprocessing.active_children() if p not in children]
        assert pool is not None and len(spawned) == 2       # both workers exist before any task is submitted
        assert os.environ.get("SETUPTOOLS_USE_DISTUTILS") == before       # this process's environment as it was
        engines.run_pool(_state, [None] * 6, lambda t, r: got.append(r), 2, None, pool)
    assert len(got) == 6 and {g["pid"] for g in got} <= set(spawned)
    for g in got:
        assert g["mcap"] and g["mrcal"] and g["kernels"] == dict.fromkeys(KERNELS, 1) | {"_apply": 1}
        assert g["env"] == "stdlib" and not g["setuptools"]     # mrcal's distutils import did not load setuptools
    assert not any(_alive(p) for p in spawned)                     # ended with the block


def test_a_pool_of_one_or_another_engine_starts_nothing():
    for engine, workers in (("pool", 1), ("inline", 4), ("dask", 2)):
        with engines.started(engine, workers, warm_up) as pool:
            assert pool is None


def test_an_exception_in_the_block_stops_the_started_workers():
    seen = []

    class Stop(Exception):
        pass

    with pytest.raises(Stop):
        with engines.started("pool", 2, None) as pool:
            engines.run_pool(_state, [None, None], lambda t, r: seen.append(r["pid"]), 2, None, pool)
            raise Stop                          # e.g. a recording that cannot be read, after the workers started
    deadline = time.monotonic() + 60
    while any(_alive(p) for p in seen) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert seen and not any(_alive(p) for p in seen)


def test_the_warm_up_loads_the_specialisations_a_real_export_uses(sim, tmp_path):
    """In a fresh process: warm up, then export the simulated recording inline; no kernel gains a signature."""
    code = (
        "import json, sys\n"
        "from pathlib import Path\n"
        "from platform_tools.dataset import chunk, register, thermal8\n"
        "from platform_tools.dataset.export import Params, export\n"
        "from platform_tools.rig import load_rig\n"
        "def sigs():\n"
        f"    d = {{n: [str(s) for s in getattr(register, n).signatures] for n in {KERNELS!r}}}\n"
        "    return d | {'_apply': [str(s) for s in thermal8._kernel().signatures]}\n"
        "chunk.warm_up()\n"
        "a = sigs()\n"
        "rig = load_rig()\n"
        "export([Path(sys.argv[1])], Path(sys.argv[2]), rig, Params.from_rig(rig, rate_hz=2), engine='inline')\n"
        "print(json.dumps([a, sigs()]))\n")
    r = subprocess.run([sys.executable, "-c", code, str(sim[0]), str(tmp_path / "out")], cwd=REPO,
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    warm, after = json.loads(r.stdout.strip().splitlines()[-1])
    assert all(len(v) == 1 for v in warm.values()), warm
    assert after == warm


def _sleep(s: float) -> float:
    time.sleep(s)
    return s


def test_an_aborted_pool_leaves_nothing_for_the_exit_hook_to_write_to(monkeypatch):
    """After close(abort=True) the executor's manager thread has ended and its wake-up pipe is closed, so
    concurrent.futures' exit hook (which writes to that pipe without a lock) has nothing to race: before, the thread
    was still closing the pipe as the interpreter exited and about one Ctrl-C in ten printed 'Exception ignored ...
    OSError: [Errno 9] Bad file descriptor' after the one-line message. The manager thread is made slow to close
    (as on a loaded machine), so that a close() which does not wait for it fails here every time."""
    from concurrent.futures import process
    slow_close = process._ExecutorManagerThread.join_executor_internals

    def slowly(self):
        time.sleep(1.0)
        slow_close(self)
    monkeypatch.setattr(process._ExecutorManagerThread, "join_executor_internals", slowly)
    pool = engines.Pool(2)
    manager = pool._pool._executor_manager_thread
    wakeup = process._threads_wakeups[manager]
    busy = [pool._pool.submit(_sleep, 30.0) for _ in range(2)]      # both workers in a task, as when Ctrl-C lands
    time.sleep(0.5)
    pool.close(abort=True)
    assert not manager.is_alive() and wakeup._closed
    assert all(f.done() for f in busy)                               # their tasks abandoned, not waited for
