"""The export's workers start before the work is known (engines.started) and are ready when it comes: the kernels
loaded by chunk.warm_up (the extension compiled ahead of time, without numba; or numba's, with the argument types of
the real call: no second specialisation), mrcal imported with the
standard library's distutils; on Linux (the default there) the workers are forked from the exporting process and each
runs the warm-up once, after the index's scans (the pool's first map, which does not wait for it) or before the first
chunk; spawned workers run it as they start; an exception in the block stops them; a process running chunks reuses
the memory it frees (workers.keep_freed_memory); the fork happens with no thread but the forking one. Checked in real
processes."""
from __future__ import annotations

import json
import multiprocessing
import os
import subprocess
import sys
import time

import numpy as np
import pytest

from platform_tools.dataset import engines, kernels
from platform_tools.dataset.chunk import warm_up
from tests.conftest import REPO

pytestmark = pytest.mark.slow          # spawned processes that import numba and mrcal


#: the kernels an export calls (platform_tools.dataset.kernels)
KERNELS = tuple(kernels.KERNELS)


def _loaded(k) -> int | str:
    """What a process holds of one kernel: 0 (not loaded), "extension", or the JIT dispatcher's count of compiled
    specialisations."""
    if k is None:
        return 0
    return "extension" if isinstance(k, kernels.Checked) else len(k.signatures)


def _state(_task=None) -> dict:
    """What a worker holds when its first task starts (run as that task, before anything else)."""
    return {"pid": os.getpid(), "mcap": "mcap.reader" in sys.modules, "mrcal": "mrcal" in sys.modules,
            "setuptools": "setuptools" in sys.modules, "numba": "numba" in sys.modules,
            "kernels": {n: _loaded(kernels._got.get(n)) for n in KERNELS},
            "env": os.environ.get("SETUPTOOLS_USE_DISTUTILS")}


def _alive(pid: int) -> bool:
    try:
        return open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


#: run in a fresh interpreter (as the export command's process is: no setuptools, no OpenCV threads): start a pool
#: with a warm-up that records where it ran, run _state as 6 tasks, print what was seen
_POOL = (
    "import functools, json, multiprocessing, os, sys\n"
    "from platform_tools.dataset import engines\n"
    "from tests.dataset.test_dataset_speed_workers import _scan_state, _state, _warm_noting\n"
    "warm = functools.partial(_warm_noting, sys.argv[1])\n"
    "got = []\n"
    "before = os.environ.get('SETUPTOOLS_USE_DISTUTILS')\n"
    "scans = []\n"
    "with engines.started('pool', 2, warm) as pool:\n"
    "    method = pool.method\n"
    "    workers = [p.pid for p in multiprocessing.active_children()]\n"
    "    env_after = os.environ.get('SETUPTOOLS_USE_DISTUTILS')\n"
    "    if sys.argv[2] == 'map':\n"
    "        scans = pool.map(_scan_state, [(k,) for k in range(5)])\n"
    "    engines.run_pool(_state, [None] * 6, lambda t, r: got.append(r), 2, None, pool)\n"
    "print(json.dumps({'parent': os.getpid(), 'workers': workers, 'got': got, 'env': [before, env_after],\n"
    "                  'parent_setuptools': 'setuptools' in sys.modules, 'scans': scans,\n"
    "                  'method': method}))\n")


def _scan_state(k: int) -> dict:
    """A map call (as the index's scans are): the first one long, so that the other worker ends its calls first and
    would take both warm-ups if nothing held it back; returns :func:`_state`."""
    if k == 0:
        time.sleep(1.0)
    return _state()


def _warm_noting(where: str) -> None:
    """chunk.warm_up, then this process's pid appended to the file ``where``."""
    warm_up()
    with open(where, "a") as f:
        f.write(f"{os.getpid()}\n")


def _pool_run(tmp_path, method: str | None = None, first: str = "run", kernels_env: str = "jit") \
        -> tuple[dict, list[int]]:
    """(what _POOL printed, the pids the warm-up ran in); ``method``: engines.START_ENV set to it; ``first``: "map"
    (5 map calls before the tasks, as the export's index) or "run" (the tasks only); ``kernels_env``: kernels.ENV
    ("jit", or the folder of an extension)."""
    where = tmp_path / "warmed"
    env = {k: v for k, v in os.environ.items() if k not in (engines.START_ENV, kernels.ENV)} \
        | ({engines.START_ENV: method} if method else {}) | {kernels.ENV: kernels_env}
    r = subprocess.run([sys.executable, "-c", _POOL, str(where), first], cwd=REPO, capture_output=True, text=True,
                       timeout=600, env=env)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout.strip().splitlines()[-1]), [int(x) for x in where.read_text().split()]


def _check_warm(out: dict, extension: bool) -> None:
    """Each task found its worker warm: the extension's kernels and no numba (``extension``), or each JIT kernel
    compiled once, for the export's argument types."""
    assert len(out["workers"]) == 2                     # both workers exist before any task is submitted
    assert out["env"][0] is None and out["env"][1] is None      # this process's environment as it was
    assert len(out["got"]) == 6 and {g["pid"] for g in out["got"]} <= set(out["workers"])
    for g in out["got"]:
        assert g["mcap"] and g["mrcal"]
        assert g["kernels"] == dict.fromkeys(KERNELS, "extension" if extension else 1)
        assert g["numba"] is not extension
        assert g["env"] == "stdlib" and not g["setuptools"]     # mrcal's distutils import did not load setuptools
    assert not any(_alive(p) for p in out["workers"])          # ended with the block


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="workers are forked on Linux only")
@pytest.mark.parametrize("method,first,extension", [(None, "map", True), (None, "map", False), ("fork", "map", True),
                                                    (None, "run", False)])
def test_forked_workers_each_warm_up_once_after_the_index(tmp_path, built, method, first, extension):
    """On Linux, by default (START_ENV unset) and with START_ENV=fork, the workers are forked from the exporting
    process without the warm-up (it loads nothing of it) and each runs it once: after the pool's first map's calls,
    which run cold (the index's scans need no kernel, and do not wait for them), or, with no map, before the first
    task. A worker done with its calls early does not take the other's warm-up (each waits for the other). With
    the extension built, no worker imports numba."""
    out, warmed = _pool_run(tmp_path, method, first, str(built) if extension else "jit")
    assert out["method"] == "fork"
    assert sorted(warmed) == sorted(out["workers"])    # once in each worker, never in the parent
    assert not out["parent_setuptools"]
    if first == "map":
        assert len(out["scans"]) == 5
        for g in out["scans"]:                         # every map call ran before any warm-up
            assert g["pid"] in out["workers"] and g["kernels"] == dict.fromkeys(KERNELS, 0) and not g["numba"]
    _check_warm(out, extension)


@pytest.mark.parametrize("extension", [True, False])
def test_spawned_workers_each_warm_up_before_their_first_task(tmp_path, built, extension):
    """With START_ENV=spawn (the default off Linux) each worker runs the warm-up as it starts."""
    out, warmed = _pool_run(tmp_path, "spawn", kernels_env=str(built) if extension else "jit")
    assert out["method"] == "spawn"
    assert sorted(warmed) == sorted(out["workers"])      # in each worker, not in the parent
    _check_warm(out, extension)


#: in a fresh interpreter (this test process may hold threads earlier tests left): the start method unset, empty,
#: then with another Python thread running, unset and set to fork, then that thread ended, unset and spawn
_DEFAULT = (
    "import json, os, threading\n"
    "from platform_tools.dataset import engines\n"
    "def m(v):\n"
    "    os.environ.pop(engines.START_ENV, None) if v is None else os.environ.__setitem__(engines.START_ENV, v)\n"
    "    return engines.start_method()\n"
    "got = [m(None), m('')]\n"
    "release = threading.Event()\n"
    "other = threading.Thread(target=release.wait, name='another')\n"
    "other.start()\n"
    "got += [m(None), m('fork')]\n"
    "release.set()\n"
    "other.join()\n"
    "got += [m(None), m('spawn')]\n"
    "print(json.dumps(got))\n")


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="workers are forked on Linux only")
def test_the_default_is_fork_unless_another_python_thread_runs():
    """Unset (or empty), START_ENV means fork on Linux, but spawn while the process runs another Python thread (a
    fork would copy only the forking thread, and any lock the other one held would stay held in every worker); a
    value given is used as it is."""
    env = {k: v for k, v in os.environ.items() if k != engines.START_ENV}
    r = subprocess.run([sys.executable, "-c", _DEFAULT], cwd=REPO, capture_output=True, text=True, timeout=120,
                       env=env)
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout.strip().splitlines()[-1]) == ["fork", "fork", "spawn", "fork", "fork", "spawn"]


#: in a fresh interpreter: OpenCV's and OpenBLAS's thread pools started as a caller of the export might have them
#: (_threaded_work), then the default pool with chunk.warm_up; at each fork, the
#: Python threads just before it and this process's native threads (/proc/self/task) just after it in the parent
#: (no thread can start in between: this thread is forking); then each worker runs an OpenCV filter and a BLAS
#: product (_threaded_work again)
_THREADS = (
    "import json, os, sys, threading\n"
    "import cv2, numpy as np\n"
    "from platform_tools.dataset import engines\n"
    "from platform_tools.dataset.chunk import warm_up\n"
    "from tests.dataset.test_dataset_speed_workers import _threaded_work\n"
    "_threaded_work()\n"
    "seen = {'python': [], 'native_after': [], 'native_before': len(os.listdir('/proc/self/task')),\n"
    "        'cv2_threads': cv2.getNumThreads()}\n"
    "os.register_at_fork(before=lambda: seen['python'].append([t.name for t in threading.enumerate()]),\n"
    "                    after_in_parent=lambda: seen['native_after'].append(len(os.listdir('/proc/self/task'))))\n"
    "got = []\n"
    "with engines.started('pool', 2, warm_up) as pool:\n"
    "    forks, method = len(seen['native_after']), pool.method\n"
    "    engines.run_pool(_threaded_work, [None] * 4, lambda t, r: got.append(r), 2, None, pool)\n"
    "seen |= {'forks': forks, 'got': got, 'method': method, 'cv2_after': cv2.getNumThreads()}\n"
    "print(json.dumps(seen))\n")


def _threaded_work(_task=None) -> float:
    """An OpenCV resize of 2000x2000 (large enough for OpenCV's thread pool: a bilateral filter or a blur of that
    size ran on one thread here) and a BLAS product of 400x400 (OpenBLAS's pool)."""
    import cv2
    import numpy as np
    a = np.random.default_rng(0).random((2000, 2000)).astype(np.float32)
    b = a[:400, :400].astype(np.float64)
    return float(cv2.resize(a, (3000, 3000)).sum() + (b @ b).sum())


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="workers are forked on Linux only")
def test_forked_workers_start_with_no_thread_but_the_forking_one():
    """The default (forked) pool forks from a process holding only its main thread: no Python thread (progress bar,
    executor manager, dask) yet, OpenCV's pool stopped for the fork (engines._opencv_single_threaded) and set back
    after, OpenBLAS's stopped by its own fork handler; the workers then use both libraries' threads and finish.
    Without _opencv_single_threaded the native count after each fork is 2 or more (tried)."""
    env = {k: v for k, v in os.environ.items() if k not in (engines.START_ENV, "OMP_NUM_THREADS",
                                                              "OPENBLAS_NUM_THREADS")}
    r = subprocess.run([sys.executable, "-c", _THREADS], cwd=REPO, capture_output=True, text=True, timeout=600,
                       env=env)
    assert r.returncode == 0, r.stderr
    seen = json.loads(r.stdout.strip().splitlines()[-1])
    assert seen["method"] == "fork" and seen["forks"] == 2
    assert seen["native_before"] > 2                 # both libraries' pools were running before the pool started
    assert seen["python"] == [["MainThread"]] * 2
    assert seen["native_after"] == [1, 1]
    assert seen["cv2_after"] == seen["cv2_threads"] > 1      # OpenCV's thread count given back to the caller
    assert len(seen["got"]) == 4 and len(set(seen["got"])) == 1


def test_an_unknown_start_method_is_one_line(monkeypatch):
    monkeypatch.setenv(engines.START_ENV, "thread")
    with pytest.raises(engines.EngineError, match=f"^{engines.START_ENV}=thread: expected spawn or fork$"):
        engines.Pool(2)


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
    """In a fresh process with numba's JIT: warm up, then export the simulated recording inline; no kernel gains a
    signature."""
    code = (
        "import json, sys\n"
        "from pathlib import Path\n"
        "from platform_tools.dataset import chunk, kernels\n"
        "from platform_tools.dataset.export import Params, export\n"
        "from platform_tools.rig import load_rig\n"
        "def sigs():\n"
        "    return {n: [str(s) for s in kernels.jit(n).signatures] for n in kernels.KERNELS}\n"
        "chunk.warm_up()\n"
        "a = sigs()\n"
        "rig = load_rig()\n"
        "export([Path(sys.argv[1])], Path(sys.argv[2]), rig, Params.from_rig(rig, rate_hz=2), engine='inline')\n"
        "print(json.dumps([a, sigs()]))\n")
    r = subprocess.run([sys.executable, "-c", code, str(sim[0]), str(tmp_path / "out")], cwd=REPO,
                       capture_output=True, text=True, timeout=600, env=os.environ | {kernels.ENV: "jit"})
    assert r.returncode == 0, r.stderr
    warm, after = json.loads(r.stdout.strip().splitlines()[-1])
    assert all(len(v) == 1 for v in warm.values()), warm
    assert after == warm


def test_with_the_extension_a_real_export_never_falls_back_to_the_jit(sim, tmp_path, built):
    """In a fresh process with the extension: export the simulated recording inline; every kernel call had exactly
    the extension's argument types (kernels.Checked sent none to the JIT), so numba was never imported, and the
    images are those of an export with numba's JIT."""
    code = (
        "import json, sys\n"
        "from pathlib import Path\n"
        "from platform_tools.dataset import kernels\n"
        "from platform_tools.dataset.export import Params, export\n"
        "from platform_tools.rig import load_rig\n"
        "rig = load_rig()\n"
        "export([Path(sys.argv[1])], Path(sys.argv[2]), rig, Params.from_rig(rig, rate_hz=2), engine='inline')\n"
        "print(json.dumps({'backend': kernels.backend(), 'jitted': sorted(kernels._jitted),\n"
        "                  'numba': 'numba' in sys.modules}))\n")
    outs = {}
    for name, env in (("extension", str(built)), ("jit", "jit")):
        outs[name] = tmp_path / name
        r = subprocess.run([sys.executable, "-c", code, str(sim[0]), str(outs[name])], cwd=REPO,
                           capture_output=True, text=True, timeout=600, env=os.environ | {kernels.ENV: env})
        assert r.returncode == 0, r.stderr
        doc = json.loads(r.stdout.strip().splitlines()[-1])
        if name == "extension":
            assert doc == {"backend": doc["backend"], "jitted": [], "numba": False}
            assert doc["backend"].startswith("extension ")
    import cv2
    pngs = sorted(p.relative_to(outs["jit"]) for p in outs["jit"].rglob("*.png"))
    assert len(pngs) > 20 and pngs == sorted(p.relative_to(outs["extension"]) for p in outs["extension"].rglob("*.png"))
    for p in pngs:
        a = cv2.imread(str(outs["jit"] / p), cv2.IMREAD_UNCHANGED)
        b = cv2.imread(str(outs["extension"] / p), cv2.IMREAD_UNCHANGED)
        assert a.dtype == b.dtype and np.array_equal(a, b), p


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


#: in a fresh interpreter: the big blocks one full-size sample allocates and frees (a registration's accumulators and
#: points, a decompressed chunk, a depth image), six rounds; prints the minor page faults of rounds 2 to 6 and the
#: pages they allocate
_FAULTS = (
    "import resource, sys\n"
    "import numpy as np\n"
    "from platform_tools.dataset.workers import keep_freed_memory\n"
    "kept = keep_freed_memory() if sys.argv[1] == 'keep' else None\n"
    "SIZES = (14_000_000, 13_000_000, 4_600_000, 2_600_000, 2_300_000)\n"
    "def one():\n"
    "    blocks = [np.ones(n // 8) for n in SIZES]\n"
    "    del blocks\n"
    "one()\n"
    "a = resource.getrusage(resource.RUSAGE_SELF).ru_minflt\n"
    "for _ in range(5):\n"
    "    one()\n"
    "print(kept, resource.getrusage(resource.RUSAGE_SELF).ru_minflt - a, 5 * sum(SIZES) // 4096)\n")


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's mallopt")
def test_a_process_that_keeps_freed_memory_reuses_its_pages():
    def run(mode: str) -> tuple[str, int, int]:
        r = subprocess.run([sys.executable, "-c", _FAULTS, mode], cwd=REPO, capture_output=True, text=True,
                           timeout=120)
        assert r.returncode == 0, r.stderr
        kept, faults, pages = r.stdout.split()
        return kept, int(faults), int(pages)
    kept, faults, pages = run("keep")
    assert kept == "True" and faults < pages // 100           # the freed pages serve the next sample's blocks
    _, faults, pages = run("default")
    assert faults > pages // 10                                 # what glibc's defaults do: fresh pages each time


def test_the_export_command_refuses_an_unknown_start_method_in_one_line(sim, tmp_path):
    out = tmp_path / "ds"
    env = dict(os.environ) | {engines.START_ENV: "threads"}
    r = subprocess.run([sys.executable, "-m", "platform_tools.cli.main", "export", str(sim[0]), "--out", str(out),
                        "--workers", "2", "-q"], cwd=REPO, capture_output=True, text=True, timeout=300, env=env)
    assert r.returncode == 2 and r.stderr.strip().splitlines() == [
        f"platform_tools: error: {engines.START_ENV}=threads: expected spawn or fork"], r.stderr
    assert not out.exists()


def test_the_export_help_names_the_default_and_the_variable():
    r = subprocess.run([sys.executable, "-m", "platform_tools.cli.main", "export", "--help"], cwd=REPO,
                       capture_output=True, text=True, timeout=120, env=dict(os.environ, COLUMNS="200"))
    assert r.returncode == 0, r.stderr
    text = " ".join(r.stdout.split())
    assert f"{engines.START_ENV}=fork|spawn" in text
    assert "forked from this process on Linux (the default there; each loads its kernels after indexing)" in text


@pytest.mark.skipif(not hasattr(os, "sched_setaffinity"), reason="no CPU affinity here")
def test_export_and_sync_check_default_to_the_cpus_they_may_use(sim, tmp_path):
    """No --workers: as many workers as the process's CPU affinity allows (a container's or taskset's limit), one
    when it allows one; the export's JSON says how many ran."""
    cpus = sorted(os.sched_getaffinity(0))

    def run(allowed, *args):
        return subprocess.run([sys.executable, "-m", "platform_tools.cli.main", *args], cwd=REPO,
                              capture_output=True, text=True, timeout=300,
                              preexec_fn=lambda: os.sched_setaffinity(0, allowed))
    assert engines.usable_cpus() == len(cpus)
    for allowed in ({cpus[0]}, set(cpus)):
        r = run(allowed, "export", str(sim[0]), "--out", str(tmp_path / f"out{len(allowed)}"), "--rate", "1", "--json")
        assert r.returncode == 0, r.stderr
        assert json.loads(r.stdout)["workers"] == len(allowed)
    one = run({cpus[0]}, "sync-check", str(sim[0]), "--json", "--set", "processing.sync_limits.max_drop_percent=6")
    every = run(set(cpus), "sync-check", str(sim[0]), "--json", "--set", "processing.sync_limits.max_drop_percent=6")
    assert one.returncode == every.returncode == 0, every.stderr
    assert json.loads(one.stdout) == json.loads(every.stdout)


#: a pool whose second warm-up to start takes 2 s: 3 map calls, then 8 tasks; prints what each did and when
_SLOW_WARM_POOL = (
    "import json, sys\n"
    "from platform_tools.dataset import engines\n"
    "from tests.dataset.test_dataset_speed_workers import _stamp, _warm_second_slowly\n"
    "with engines.started('pool', 2, _warm_second_slowly) as pool:\n"
    "    pool.map(_stamp, [('scan',)] * 3)\n"
    "    got = []\n"
    "    engines.run_pool(_stamp, [('task',)] * 8, lambda t, r: got.append(r), 2, None, pool)\n"
    "print(json.dumps(got))\n")


def _warm_second_slowly() -> None:
    """A warm-up that records its pid and times, and takes 2 s in the worker that starts it second."""
    import fcntl
    path = os.environ["WARM_LOG"]
    with open(path, "a+") as f:
        fcntl.flock(f, fcntl.LOCK_EX)
        f.seek(0)
        second = len(f.read().split()) > 0
        f.write(f"{os.getpid()}\n")
    start = time.time()
    if second:
        time.sleep(2.0)
    with open(path + ".times", "a") as f:
        f.write(json.dumps({"pid": os.getpid(), "start": start, "end": time.time()}) + "\n")


def _stamp(what) -> dict:
    """A call that records where and when it ran."""
    time.sleep(0.05)
    return {"pid": os.getpid(), "at": time.time(), "what": what}


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="workers are forked on Linux only")
def test_a_worker_whose_warm_up_ends_first_starts_the_tasks_without_waiting_for_the_other(tmp_path):
    """Each forked worker takes one warm-up and waits only until the other has taken its own (not until it is done),
    so a worker ready first runs the queued tasks while the other still loads its kernels; no task runs in a worker
    before its own warm-up ended."""
    log = tmp_path / "warm"
    env = {k: v for k, v in os.environ.items() if k != engines.START_ENV} | {"WARM_LOG": str(log)}
    r = subprocess.run([sys.executable, "-c", _SLOW_WARM_POOL], cwd=REPO, capture_output=True, text=True,
                       timeout=600, env=env)
    assert r.returncode == 0, r.stderr
    tasks = json.loads(r.stdout.strip().splitlines()[-1])
    warms = {w["pid"]: w for w in map(json.loads, (tmp_path / "warm.times").read_text().splitlines())}
    assert len(warms) == 2 and len(tasks) == 8                      # one warm-up in each worker
    slow = max(warms.values(), key=lambda w: w["end"] - w["start"])
    assert slow["end"] - slow["start"] >= 2.0
    assert all(t["at"] >= warms[t["pid"]]["end"] for t in tasks)     # none ran cold
    early = [t for t in tasks if t["at"] < slow["end"]]
    assert early and all(t["pid"] != slow["pid"] for t in early)     # the other worker did not wait for it


def test_the_warm_up_loads_numbas_registries_without_scipy_linalg_and_the_outputs_stay_the_same(sim, tmp_path):
    """Fresh processes with numba's JIT kernels (kernels.ENV=jit), each warming up then exporting the simulated
    recording inline: the warm-up's process never imports scipy.linalg (numba's BLAS probe, engines.numba_without_blas_probe), even after the export; a process
    that imported the probe first (numba's usual start: its BLAS check passes) writes the same images, byte for
    byte."""
    code = (
        "import json, sys\n"
        "from pathlib import Path\n"
        "if sys.argv[3] == 'probe':\n"
        "    import scipy.linalg.cython_blas\n"
        "from platform_tools.dataset import chunk\n"
        "from platform_tools.dataset.export import Params, export\n"
        "from platform_tools.rig import load_rig\n"
        "chunk.warm_up()\n"
        "import numba.np.arraymath\n"
        "rig = load_rig()\n"
        "export([Path(sys.argv[1])], Path(sys.argv[2]), rig, Params.from_rig(rig, rate_hz=2), engine='inline')\n"
        "print(json.dumps({'blas': numba.np.arraymath._HAVE_BLAS, 'scipy.linalg': 'scipy.linalg' in sys.modules}))\n")
    got, images = {}, {}
    for how in ("probe", "none"):
        out = tmp_path / how
        r = subprocess.run([sys.executable, "-c", code, str(sim[0]), str(out), how], cwd=REPO,
                           capture_output=True, text=True, timeout=600, env=os.environ | {kernels.ENV: "jit"})
        assert r.returncode == 0, r.stderr
        got[how] = json.loads(r.stdout.strip().splitlines()[-1])
        images[how] = {p.relative_to(out): p.read_bytes() for p in out.rglob("*")
                       if p.suffix in (".png", ".jpg", ".npy")}
    assert got == {"probe": {"blas": True, "scipy.linalg": True}, "none": {"blas": False, "scipy.linalg": False}}
    assert len(images["none"]) > 20
    assert images["none"] == images["probe"]


def test_the_blas_probe_is_never_left_unimportable():
    """numba_without_blas_probe in fresh processes: it does nothing where numba's arraymath is imported already, and
    where that import fails (a numba that needs the probe, stood in for by a finder refusing arraymath) the probe is
    importable again after it."""
    code = (
        "import json, sys\n"
        "from platform_tools.dataset import engines\n"
        "class Refuse:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name == 'numba.np.arraymath':\n"
        "            raise ImportError('stand-in: a numba whose arraymath needs the probe')\n"
        "if sys.argv[1] == 'fails':\n"
        "    sys.meta_path.insert(0, Refuse())\n"
        "else:\n"
        "    import numba.np.arraymath\n"
        "first = engines.numba_without_blas_probe()\n"
        "left = sys.modules.get(engines.BLAS_PROBE, 'absent')\n"
        "print(json.dumps([first, left if left in ('absent', None) else 'module']))\n")
    # imported already: numba imported the probe itself, and it stays as it was
    for how, want in (("fails", [False, "absent"]), ("imported", [False, "module"])):
        r = subprocess.run([sys.executable, "-c", code, how], cwd=REPO, capture_output=True, text=True, timeout=120)
        assert r.returncode == 0, r.stderr
        assert json.loads(r.stdout.strip().splitlines()[-1]) == want, how
