"""Where the export's chunks run: ``inline`` (this process), ``pool`` (a concurrent.futures process pool) or
``dask`` (dask.distributed: a LocalCluster, or a running scheduler by address; its workers must see the
recordings and the output folder at the same paths).

Each engine is ``run(work, tasks, finished, workers, scheduler)``: it calls ``work(task)`` for every task and
``finished(task, result)`` in this process as each one ends, in any order.
"""
from __future__ import annotations

from platform_tools.rig.progress import progress


class EngineError(Exception):
    """An engine that cannot run here; one line."""


def _bar(n: int):
    return progress(range(n), desc="export", total=n, unit="chunk")


def run_inline(work, tasks, finished, workers, scheduler) -> None:
    bar = iter(_bar(len(tasks)))
    for t in tasks:
        finished(t, work(t))
        next(bar, None)


def run_pool(work, tasks, finished, workers, scheduler) -> None:
    """A process pool of spawned workers that end with this process (workers.die_with_parent). On any error or
    interrupt (SIGINT) here, the queued tasks are cancelled and every worker is stopped at once (a task in flight is
    abandoned, its chunk redone on resume) before the exception goes on."""
    if workers <= 1:
        return run_inline(work, tasks, finished, workers, scheduler)
    import multiprocessing
    import os
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

    from .workers import die_with_parent, stop
    bar = iter(_bar(len(tasks)))
    ctx = multiprocessing.get_context("spawn")     # no fork of a process holding numba / threads
    before = set(multiprocessing.active_children())
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=die_with_parent,
                               initargs=(os.getpid(),))
    try:
        pending = {pool.submit(work, t): t for t in tasks}
        while pending:
            done, _ = wait(pending, return_when=FIRST_COMPLETED)
            for f in done:
                t = pending.pop(f)
                finished(t, f.result())
                next(bar, None)
    except BaseException:
        mine = [p for p in multiprocessing.active_children() if p not in before]
        pool.shutdown(wait=False, cancel_futures=True)
        stop(mine)
        raise
    pool.shutdown(wait=True)


def run_dask(work, tasks, finished, workers, scheduler) -> None:
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
