"""SIGINT and SIGTERM in the export's process (platform_tools.dataset.interrupts): held while a block runs, run where
the block says; and the pool (engines.Pool) stopped whole by a SIGTERM landing on any line its main thread runs in
concurrent.futures (tests/dataset/interrupt_probe.py), which a SIGTERM in concurrent.futures.wait did not (CI,
stop 38: an export that SIGTERM never ended)."""
from __future__ import annotations

import json
import queue
import signal
import subprocess
import sys
import threading

import pytest

from platform_tools.dataset.interrupts import held
from tests.conftest import REPO


class Came(Exception):
    """What this test's own handlers raise: a handler that ran where it should not shows up as one."""


@pytest.fixture
def outer():
    """This test's handlers outside the blocks (the suite's own are put back after): SIGTERM raises Came, SIGINT
    only records; the list of the signals whose outer handler ran."""
    ran: list[int] = []

    def raising(signum, frame):
        ran.append(signum)
        raise Came(signum)

    old = {signal.SIGTERM: signal.signal(signal.SIGTERM, raising),
           signal.SIGINT: signal.signal(signal.SIGINT, lambda signum, frame: ran.append(signum))}
    try:
        yield ran
    finally:
        for sig, h in old.items():
            signal.signal(sig, h)


def test_a_held_signal_runs_where_the_block_delivers_it(outer):
    wakes = queue.SimpleQueue()
    with pytest.raises(Came):
        with held(wake=lambda: wakes.put(1)) as deliver:
            signal.raise_signal(signal.SIGTERM)
            assert outer == [] and wakes.get_nowait() == 1      # recorded and woke, its handler not run
            with pytest.raises(Came):
                deliver()
            assert outer == [signal.SIGTERM]
            signal.raise_signal(signal.SIGTERM)                  # the block still holds after a delivery
            assert outer == [signal.SIGTERM]
    assert outer == [signal.SIGTERM, signal.SIGTERM]            # the second one ran as the block ended
    assert signal.getsignal(signal.SIGTERM).__name__ == "raising"     # the outer handler is back


def test_what_is_still_held_runs_when_the_block_ends(outer):
    with pytest.raises(Came):
        with held() as deliver:
            signal.raise_signal(signal.SIGTERM)
            signal.raise_signal(signal.SIGTERM)
            assert outer == [] and deliver.came == [signal.SIGTERM, signal.SIGTERM]
    assert outer == [signal.SIGTERM]            # one interrupt, raised once


def test_nothing_held_nothing_run(outer):
    with held() as deliver:
        deliver()
    assert outer == []


def test_an_ignored_signal_stays_ignored(outer):
    signal.signal(signal.SIGINT, signal.SIG_IGN)          # a background job's SIGINT
    with held() as deliver:
        signal.raise_signal(signal.SIGINT)
        deliver()                                           # runs SIG_IGN: nothing
    assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN and outer == []


def test_blocks_nest_and_an_inner_leftover_goes_to_the_outer_block(outer):
    with held() as deliver:
        with held():
            signal.raise_signal(signal.SIGTERM)
        assert outer == [] and deliver.came == [signal.SIGTERM]
        with pytest.raises(Came):
            deliver()
    assert outer == [signal.SIGTERM]


def test_outside_the_main_thread_the_block_changes_nothing(outer):
    seen = []

    def other():
        with held() as deliver:
            seen.append(signal.getsignal(signal.SIGTERM).__name__)
            deliver()
    t = threading.Thread(target=other)
    t.start()
    t.join()
    assert seen == ["raising"]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="forked workers")
def test_a_sigterm_on_any_line_of_concurrent_futures_stops_the_pool_whole():
    r = subprocess.run([sys.executable, "-m", "tests.dataset.interrupt_probe", "fork"], cwd=REPO,
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    assert r.stderr == ""                       # no worker traceback (a worker stopped before its initializer)
    head, *results = map(json.loads, r.stdout.splitlines())
    assert len(results) > 100 and any(x["hit"] == 2 for x in results), head
    # the old pool's lock-taking loops (concurrent.futures.wait's) are gone; the futures' own locks are still probed
    assert any(x["line"][:2] == ["_base.py", "add_done_callback"] for x in results)
    bad = [x for x in results
           if not (x["fired"] and x["interrupted"]) or x["error"] or x["manager_alive"] or x["children"]]
    assert bad == [], bad[:5]
