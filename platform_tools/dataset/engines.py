"""Where the export's chunks run: ``inline`` (this process), ``pool`` (a concurrent.futures process pool) or
``dask`` (dask.distributed: a LocalCluster, or a running scheduler by address; its workers must see the
recordings and the output folder at the same paths).

Each engine is ``run(work, tasks, finished, workers, scheduler, pool=None)``: it calls ``work(task)`` for every task
and ``finished(task, result)`` in this process as each one ends, in any order. ``pool``: the pool's workers
:func:`started` earlier (only the pool engine uses it).
"""
from __future__ import annotations

import contextlib

from platform_tools.rig.progress import progress


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


class Pool:
    """A process pool of spawned workers that end with this process (workers.die_with_parent), started at once:
    each worker runs ``warm_up`` (imports, numba's kernels loaded) as soon as it exists, so that its start-up
    (about 3 s of CPU at full size, docs/dataset.md "Speed") overlaps what this process does before the first task
    (indexing the recordings) instead of following it. :meth:`run` runs tasks; :meth:`close` ends the workers."""

    def __init__(self, workers: int, warm_up=None):
        import multiprocessing
        import os
        from concurrent.futures import ProcessPoolExecutor
        ctx = multiprocessing.get_context("spawn")     # no fork of a process holding numba / threads
        self._before = set(multiprocessing.active_children())
        self._pool = ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=_start_worker,
                                         initargs=(os.getpid(), warm_up))
        self._closed = False
        with _worker_environment():
            for _ in range(workers):    # the executor spawns a process per submission while none is idle: all now
                self._pool.submit(_nothing)

    def run(self, work, tasks, finished) -> None:
        """``work(task)`` for every task, ``finished(task, result)`` here as each ends. On any error or interrupt
        (SIGINT) here, the queued tasks are cancelled and every worker is stopped at once (a task in flight is
        abandoned, its chunk redone on resume) before the exception goes on."""
        from concurrent.futures import FIRST_COMPLETED, wait
        bar = iter(_bar(len(tasks)))
        try:
            pending = {self._pool.submit(work, t): t for t in tasks}
            while pending:
                done, _ = wait(pending, return_when=FIRST_COMPLETED)
                for f in done:
                    t = pending.pop(f)
                    finished(t, f.result())
                    next(bar, None)
        except BaseException:
            self.close(abort=True)
            raise

    def close(self, abort: bool = False) -> None:
        """Let the workers finish and end (``abort``: cancel what is queued and stop them now); once."""
        if self._closed:
            return
        self._closed = True
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
        if manager is not None:
            manager.join(MANAGER_JOIN_S)


def _nothing() -> None:
    return None


#: the environment a spawned worker starts with, beyond this process's: setuptools' documented switch to the
#: standard library's distutils. mrcal's numpysane imports distutils.version; in a virtualenv setuptools' import
#: hook otherwise answers with setuptools' own copy, importing setuptools (0.4 s of CPU per process, measured)
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


def _start_worker(parent_pid: int, warm_up) -> None:
    """The pool's initializer: end with the parent, then get ready for work. A warm-up that fails is only a missed
    head start: the task that needs what it loads fails with the real error."""
    from .workers import die_with_parent
    die_with_parent(parent_pid)
    if warm_up is not None:
        try:
            warm_up()
        except Exception:           # noqa: BLE001 - see the docstring
            pass


@contextlib.contextmanager
def started(engine: str, workers: int, warm_up=None):
    """The engine's workers started now, for :func:`run_pool` (``pool=``) later; None for engines that start their
    own (inline, dask) or a pool of one. The workers are stopped when the block ends with an exception, let finish
    otherwise."""
    pool = Pool(workers, warm_up) if engine == "pool" and workers > 1 else None
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
