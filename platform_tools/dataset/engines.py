"""Where the export's chunks run: ``inline`` (this process), ``pool`` (a concurrent.futures process pool) or
``dask`` (dask.distributed: a LocalCluster, or a running scheduler by address; its workers must see the
recordings and the output folder at the same paths).

Each engine is ``run(work, tasks, finished, workers, scheduler, pool=None)``: it calls ``work(task)`` for every task
and ``finished(task, result)`` in this process as each one ends, in any order. ``pool``: the pool's workers
:func:`started` earlier (only the pool engine uses it).
"""
from __future__ import annotations

import contextlib
import queue
import sys
from concurrent.futures.process import BrokenProcessPool

from platform_tools.rig.interrupts import held
from platform_tools.rig.progress import progress
from .workers import forking_workers


class EngineError(Exception):
    """An engine that cannot run here; one line."""


def _bar(n: int):
    return progress(range(n), desc="export", total=n, unit="chunk")


def run_inline(work, tasks, finished, workers, scheduler, pool=None) -> None:
    bar = iter(_bar(len(tasks)))
    for t in tasks:
        finished(t, work(t))
        next(bar, None)


#: how long an aborted pool waits for its executor's manager thread to end (it ends once it sees the workers gone)
MANAGER_JOIN_S = 10.0


#: how the pool's workers start (this variable, read when a pool starts): "fork" (the default on Linux), the workers
#: forked from this process, sharing the imports it has (a spawned worker's cost about 0.7 s of CPU each at full size,
#: docs/dataset.md "Speed"), each running the warm-up once after the index's scans (Pool), or "spawn" (the default
#: elsewhere), each worker a fresh interpreter running the warm-up as it starts
START_ENV = "PLATFORM_TOOLS_EXPORT_WORKERS"
START_METHODS = ("spawn", "fork")


def usable_cpus() -> int:
    """The CPUs this process may run on (its affinity mask: a container's or taskset's limit, not the machine's
    count): the default number of workers of export and sync-check."""
    import os
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:                  # no sched_getaffinity (macOS, Windows)
        return max(1, os.cpu_count() or 1)


def default_start_method() -> str:
    """The start method when START_ENV is unset: "fork" on Linux, "spawn" elsewhere (Windows has no fork; on macOS
    forking a process that loaded system frameworks is unsafe). Also "spawn" in a process already running other
    Python threads (a notebook's, a server's, the caller's own): a forked child holds only the forking thread, and a
    lock another thread held at that moment (logging's, an import's) would stay held in every worker. The export
    command starts its pool before any thread of its own (no progress bar yet, no dask) and stops OpenCV's thread
    pool while forking (:func:`_opencv_single_threaded`); OpenBLAS, the other native thread pool here, stops its
    threads itself before a fork (its pthread_atfork handler)."""
    import threading
    return "fork" if sys.platform.startswith("linux") and threading.active_count() == 1 else "spawn"


def start_method() -> str:
    """The workers' start method START_ENV asks for (:func:`default_start_method` when unset or empty); an unknown
    value is one line."""
    import os
    method = os.environ.get(START_ENV) or default_start_method()
    if method not in START_METHODS:
        raise EngineError(f"{START_ENV}={method}: expected {' or '.join(START_METHODS)}")
    if method == "fork" and not sys.platform.startswith("linux"):
        raise EngineError(f"{START_ENV}=fork: workers are forked on Linux only; leave it unset or set it to spawn")
    return method


def _died(exc: Exception) -> EngineError:
    """A worker that died (a signal, the kernel's out-of-memory killer) as one line, with what to do."""
    return EngineError(f"a worker process died ({exc}); the kernel's log says why (dmesg: out of memory?); run "
                       f"again with fewer --workers (each holds a few hundred MB at full size)")


class Pool:
    """A process pool of workers that end with this process (workers.die_with_parent), started at once. ``warm_up``
    (imports, numba's kernels loaded; no OpenCV call) runs in each spawned worker as it starts; forked workers
    (``method`` "fork", :func:`start_method`) run it once each after the calls of the first :meth:`map` (the index's
    chunk scans, which do not need it), while this process plans the work from what the map returned, and before
    the first :meth:`run`'s tasks. ``preload`` (imports the map's calls need) runs here before the workers are
    forked. :meth:`map` runs calls, :meth:`run` tasks; :meth:`close` ends the workers."""

    def __init__(self, workers: int, warm_up=None, method: str | None = None, preload=None):
        import multiprocessing
        import os
        from concurrent.futures import ProcessPoolExecutor
        method = method or start_method()
        self.method = method                #: "spawn" or "fork", as the workers were started
        self.workers = workers              #: how many workers run
        ctx = multiprocessing.get_context(method)
        self._before = set(multiprocessing.active_children())
        forked = method == "fork"
        self._closed = False
        #: the warm-up each forked worker still has to run (:meth:`_warm_workers`); None once submitted
        self._deferred = warm_up if forked else None
        #: how many forked workers have taken their warm-up, and the condition one that has run it waits on until
        #: every worker has taken its own (_warm_worker)
        warm_count = (ctx.RawValue("i", 0), ctx.Condition(), workers) if self._deferred is not None else None
        with _worker_environment(), (_opencv_single_threaded() if forked else contextlib.nullcontext()):
            if forked and preload is not None:
                with stdlib_distutils():
                    _warm(preload)          # here: the forked workers inherit what it loaded
            # held while they start: an interrupt then stops the workers started so far (below), and a worker
            # forked now inherits a handler that only records until it takes its own, at the fork
            # (workers.forking_workers): with the export's, a worker stopped at once printed a traceback
            with held() as deliver:
                self._pool = ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=_start_worker,
                                                 initargs=(os.getpid(), None if forked else warm_up, warm_count))
                try:
                    with forking_workers():
                        for _ in range(workers):    # all started now (a forking executor starts them at the first)
                            self._pool.submit(_nothing)
                    deliver()
                except BaseException:           # an interrupt while they start: none is left behind
                    self.close(abort=True)
                    raise

    def _warm_workers(self) -> None:
        """Queue each forked worker's warm-up (once): one call per worker, each of which waits for the others
        (the count passed to :func:`_start_worker`), so that no worker takes two and leaves another cold."""
        if self._deferred is None:
            return
        warm_up, self._deferred = self._deferred, None
        for _ in range(self.workers):
            self._pool.submit(_warm_worker, warm_up)

    def run(self, work, tasks, finished) -> None:
        """``work(task)`` for every task, ``finished(task, result)`` here as each ends. On any error or interrupt
        (SIGINT, or SIGTERM where the command turns it into one), the queued tasks are cancelled and every worker
        is stopped at once (a task in flight is abandoned, its chunk redone on resume) before the exception goes
        on."""
        bar = iter(_bar(len(tasks)))

        def ended(k: int, f) -> None:
            finished(tasks[k], f.result())
            next(bar, None)
        self._each_end([(work, (t,)) for t in tasks], ended, warm_first=True, keep_on_error=False)

    def map(self, fn, args: list[tuple], done=None) -> list:
        """``fn(*a)`` for each ``a`` of ``args`` in the workers, the results in that order (the index's chunk scans,
        :mod:`.indexscan`); ``done(k)`` is called here as the k-th ends (a progress bar). An error of ``fn`` cancels
        what is queued and goes on here; an interrupt stops every worker (as :meth:`run`)."""
        def ended(k: int, f) -> None:
            f.result()                          # an error ends the map now
            if done is not None:
                done(k)
        futures = self._each_end([(fn, a) for a in args], ended, warm_first=False, keep_on_error=True)
        return [f.result() for f in futures]

    def _each_end(self, calls: list[tuple], ended, warm_first: bool, keep_on_error: bool) -> list:
        """``fn(*a)`` for each ``(fn, a)`` of ``calls`` in the workers, and ``ended(k, future)`` here as the k-th
        ends; the futures, in order. Each forked worker's warm-up is queued before the calls (``warm_first``: a run
        with no map before it) or after them (the map's scans do not need it). The wait is a queue that each
        future's done-callback feeds, and SIGINT / SIGTERM are held meanwhile and run between two ends, never
        inside concurrent.futures (platform_tools.rig.interrupts: its wait, which takes every pending future's lock
        in turn, left some taken when a handler raised there). On an error the queued calls are cancelled, and the
        workers stopped unless ``keep_on_error`` (an exception of a call, or of ``ended``); on an interrupt or a
        dead worker they are stopped."""
        ends = queue.SimpleQueue()          # the futures as they end, and a signal's wake-up (None)
        futures = []
        with held(wake=lambda signum: ends.put(None)) as deliver:
            try:
                if warm_first:
                    self._warm_workers()
                for fn, a in calls:
                    f = self._pool.submit(fn, *a)
                    futures.append(f)
                    f.add_done_callback(ends.put)
                if not warm_first:
                    self._warm_workers()        # each worker, once its last call is done
                place = {f: k for k, f in enumerate(futures)}
                left = len(futures)
                while left:
                    deliver()
                    f = ends.get()
                    if f is not None:
                        left -= 1
                        ended(place[f], f)
                deliver()
                return futures
            except BrokenProcessPool as exc:
                self.close(abort=True)
                raise _died(exc) from None
            except Exception:
                if not keep_on_error:
                    self.close(abort=True)
                for f in futures:
                    f.cancel()
                raise
            except BaseException:
                self.close(abort=True)
                raise

    def close(self, abort: bool = False) -> None:
        """Let the workers finish and end (``abort``: cancel what is queued and stop them now); once."""
        if self._closed:
            return
        self._closed = True
        with held():                    # a second Ctrl-C while they stop acts once they have stopped
            self._close(abort)

    def _close(self, abort: bool) -> None:
        if not abort:
            self._pool.shutdown(wait=True)
            return
        import multiprocessing

        from .workers import stop
        mine = [p for p in multiprocessing.active_children() if p not in self._before]
        # The executor's manager thread sees its workers gone and closes its wake-up pipe. Left running, it races
        # concurrent.futures' exit hook, which writes to that pipe unlocked: "Exception ignored ... OSError: [Errno
        # 9] Bad file descriptor" after the one-line interrupt message (seen once in about ten Ctrl-C tests). It is
        # taken before shutdown(wait=False), which drops the executor's reference to it.
        manager = getattr(self._pool, "_executor_manager_thread", None)
        self._pool.shutdown(wait=False, cancel_futures=True)
        stop(mine)
        if manager is not None and manager.ident is not None:     # None: interrupted before it started
            manager.join(MANAGER_JOIN_S)


def _nothing() -> None:
    return None


#: the environment the warm-up runs in and a worker starts with, beyond this process's: setuptools' documented switch
#: to the standard library's distutils. mrcal's numpysane imports distutils.version; in a virtualenv setuptools'
#: import hook otherwise answers with setuptools' own copy, importing setuptools (0.4 s of CPU per process, measured)
WORKER_ENVIRONMENT = {"SETUPTOOLS_USE_DISTUTILS": "stdlib"}


@contextlib.contextmanager
def _worker_environment():
    """os.environ with WORKER_ENVIRONMENT while workers are spawned (a spawned process inherits it), restored
    after; a variable the user set is left as it is."""
    import os
    added = {k: v for k, v in WORKER_ENVIRONMENT.items() if k not in os.environ}
    os.environ.update(added)
    try:
        yield
    finally:
        for k in added:
            os.environ.pop(k, None)


def _warm(warm_up) -> None:
    """Run a warm-up; one that fails is only a missed head start: the task that needs what it loads fails with the
    real error."""
    try:
        warm_up()
    except Exception:           # noqa: BLE001 - see the docstring
        pass


@contextlib.contextmanager
def stdlib_distutils():
    """setuptools' distutils finder (installed at start-up unless SETUPTOOLS_USE_DISTUTILS=stdlib) out of the import
    path for the block: what WORKER_ENVIRONMENT does for a spawned process, for imports in this one (mrcal's, through
    numpysane), where the variable is read too late to count: importing mrcal then costs about 0.1 s of CPU instead
    of 0.2 s. A process that imports setuptools later gets its distutils then, as setuptools replaces an already
    imported one itself."""
    hooks = [f for f in sys.meta_path if type(f).__module__ == "_distutils_hack"]
    for f in hooks:
        sys.meta_path.remove(f)
    try:
        yield
    finally:
        sys.meta_path[:0] = [f for f in hooks if f not in sys.meta_path]


#: what numba's array functions import, when the first kernel loads numba's registries, to ask whether BLAS is there
#: (numba.np.arraymath's _check_blas): it imports scipy.linalg whole, 0.16 of a worker's 0.5 s of CPU warming up
#: (py-spy of a full-size export at 1 Hz, then timed alone, 2026-12-05). No kernel of this package calls BLAS; where
#: the import fails numba uses its own loop for the one thing that check gates (np.correlate's and np.convolve's
#: inner product); np.dot and np.linalg ask for BLAS again when they are compiled (numba.np.linalg.ensure_blas)
BLAS_PROBE = "scipy.linalg.cython_blas"


def numba_without_blas_probe() -> bool:
    """Import numba's array functions (numba.np.arraymath) with BLAS_PROBE unimportable, so that loading numba's
    registries does not import scipy.linalg: once per process, before its first kernel (:func:`.chunk.warm_up`).
    Nothing where either is imported already; a numba whose arraymath cannot import without the probe imports it
    later as usual, with it. True when numba's arraymath was imported without the probe."""
    if BLAS_PROBE in sys.modules or "numba.np.arraymath" in sys.modules:
        return False
    sys.modules[BLAS_PROBE] = None          # an import of it raises ImportError (the import system's documented rule)
    try:
        import numba.np.arraymath  # noqa: F401 - for its import-time check, made without scipy.linalg
        return True
    except ImportError:
        return False
    finally:
        if BLAS_PROBE in sys.modules and sys.modules[BLAS_PROBE] is None:
            del sys.modules[BLAS_PROBE]


@contextlib.contextmanager
def _opencv_single_threaded():
    """OpenCV's thread pool stopped (``cv2.setNumThreads(1)`` joins its threads) while workers are forked, then set
    back: a forked child holds only the forking thread, and an OpenCV whose pool threads are gone would wait for
    them. (OpenBLAS, the other library here with threads, numpy's and scipy's copies alike, shuts its threads down
    before a fork itself: tests/dataset/test_dataset_speed_workers.py counts the threads left at each fork.)"""
    import cv2
    n = cv2.getNumThreads()
    cv2.setNumThreads(1)
    try:
        yield
    finally:
        cv2.setNumThreads(n)


#: (warm-ups taken, its condition, workers) of the pool, which a forked worker waits on after its warm-up
#: (:func:`_warm_worker`), set by :func:`_start_worker`
_warm_count: list = []
#: how long a warm worker waits for the others to take their warm-up; a worker still busy after it warms up in its
#: next task instead (numba loads its kernels at their first call)
WARM_WAIT_S = 10.0


def _start_worker(parent_pid: int, warm_up, warm_count=None) -> None:
    """The pool's initializer: end with the parent, then (a spawned worker) get ready for work; (a forked one) keep
    the warm-up count of :func:`_warm_worker`."""
    from .workers import die_with_parent
    die_with_parent(parent_pid)
    _warm_count[:] = [warm_count] if warm_count is not None else []
    if warm_up is not None:
        _warm(warm_up)


def _warm_worker(warm_up) -> None:
    """A forked worker's warm-up (Pool._warm_workers), then a wait until every worker has taken its own (started it:
    a worker still loading its kernels takes no task before it is done, so none runs cold). Waiting until the others
    had finished theirs kept a worker that ended its scans early idle while the samples were queued: 0.6 s of a 15 s
    export on this project's 60 s recording, docs/dataset.md "Speed"."""
    if _warm_count:
        taken, cond, workers = _warm_count[0]
        with cond:
            taken.value += 1
            cond.notify_all()
    with stdlib_distutils():
        _warm(warm_up)
    if _warm_count:
        with cond:          # a worker that does not come in time (busy, or gone): go on, it warms up in its task
            cond.wait_for(lambda: taken.value >= workers, WARM_WAIT_S)


@contextlib.contextmanager
def started(engine: str, workers: int, warm_up=None, preload=None):
    """The engine's workers started now (:class:`Pool`), for :func:`run_pool` (``pool=``) later; None for engines
    that start their own (inline, dask) or a pool of one. The workers are stopped when the block ends with an
    exception, let finish otherwise."""
    pool = Pool(workers, warm_up, preload=preload) if engine == "pool" and workers > 1 else None
    try:
        yield pool
    except BaseException:
        if pool is not None:
            pool.close(abort=True)
        raise
    if pool is not None:
        pool.close()


def run_pool(work, tasks, finished, workers, scheduler, pool: Pool | None = None) -> None:
    """The tasks on a process pool (:class:`Pool`): ``pool`` if one was :func:`started`, else one started now."""
    if pool is None and workers <= 1:
        return run_inline(work, tasks, finished, workers, scheduler)
    own = pool is None
    pool = pool or Pool(workers)
    pool.run(work, tasks, finished)
    if own:
        pool.close()


def run_dask(work, tasks, finished, workers, scheduler, pool=None) -> None:
    try:
        from distributed import Client, LocalCluster, as_completed
    except ImportError:
        raise EngineError("--engine dask needs dask.distributed (pip install 'dask[distributed]')") from None
    cluster = None
    if scheduler:
        client = Client(scheduler)
    else:
        cluster = LocalCluster(n_workers=max(1, workers), threads_per_worker=1, processes=True,
                               dashboard_address=None)
        client = Client(cluster)
    try:
        bar = iter(_bar(len(tasks)))
        futures = client.map(work, tasks, pure=False)
        by_key = {f.key: t for f, t in zip(futures, tasks)}
        for f in as_completed(futures):
            finished(by_key[f.key], f.result())
            next(bar, None)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


ENGINES = {"inline": run_inline, "pool": run_pool, "dask": run_dask}
