"""platform_tools.rig.interrupts.held: SIGINT and SIGTERM recorded while a block runs, their handlers run where the
block delivers them or as it ends; ignored signals left ignored; blocks nest. Each test sets its own handlers
outside the blocks (put back after), so that a handler run at the wrong place shows up as one, not as the test
run's own Ctrl-C."""
from __future__ import annotations

import queue
import signal
import threading

import pytest

from platform_tools.rig.interrupts import held


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
        with held(wake=wakes.put) as deliver:
            signal.raise_signal(signal.SIGTERM)
            assert outer == [] and wakes.get_nowait() == signal.SIGTERM      # recorded and woke, its handler not run
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
        assert deliver.came == [] and signal.getsignal(signal.SIGINT) is signal.SIG_IGN    # not even recorded
        deliver()
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
