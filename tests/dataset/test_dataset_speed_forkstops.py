"""Clean stops with forked workers (``PLATFORM_TOOLS_EXPORT_WORKERS=fork``, engines.start_method): the scenarios of
test_dataset_stops.py on a real `platform_tools export --workers 2` process whose workers are forked from it after
its warm-up. A forked worker inherits the export command's SIGTERM handler (SIGTERM turned into an interrupt) and
its command line; workers.die_with_parent sets SIGTERM back to its default, so that SIGTERM (workers.stop) ends a
worker at once as it ends a spawned one, rather than raising in its task. The workers are found here as the parent's
children (there is no resource tracker with fork)."""
from __future__ import annotations

import os
import signal
import sys

import pytest

from platform_tools.dataset.engines import START_ENV
from tests.dataset.test_dataset_stops import (WAIT_S, _children, _markers, _resume_equals_reference, _running,
                                              _start, _wait)
from tests.dataset.test_dataset_stops import reference  # noqa: F401 - the fixture, shared with those tests

pytestmark = [pytest.mark.slow, pytest.mark.skipif(not sys.platform.startswith("linux"), reason="fork; /proc")]


@pytest.fixture()
def forked(monkeypatch):
    """The export processes started in the test fork their workers (the variable is inherited)."""
    monkeypatch.setenv(START_ENV, "fork")


def _forked_workers(p) -> list[int]:
    """The pool's two workers: the parent's children, carrying its own command line (forked, not spawned)."""
    kids = _children(p.pid)
    own = open(f"/proc/{p.pid}/cmdline", "rb").read().replace(b"\0", b" ").decode()
    assert len(kids) == 2 and all(cmd == own for cmd in kids.values()), kids
    return list(kids)


@pytest.mark.parametrize("how", ["ctrl-c", "sigterm"])
def test_an_interrupt_stops_every_forked_worker_and_the_export_resumes_identical(sim, reference, forked, how):  # noqa: F811
    base, ref = reference
    out = base / "ds"
    p = _start(sim[0], out)
    workers = _forked_workers(p)
    if how == "ctrl-c":
        os.killpg(p.pid, signal.SIGINT)
    else:
        os.kill(p.pid, signal.SIGTERM)
    _, err = p.communicate(timeout=WAIT_S)
    assert p.returncode == 130, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "interrupted" in lines[0] and str(out) in lines[0], err   # no worker traceback
    assert [w for w in workers if _running(w)] == []
    assert not list(out.rglob("*.tmp"))
    _resume_equals_reference(sim[0], out, ref)


def test_forked_workers_end_when_the_parent_is_killed(sim, reference, forked):  # noqa: F811
    base, ref = reference
    out = base / "ds"
    p = _start(sim[0], out)
    workers = _forked_workers(p)
    p.kill()
    p.wait()
    _wait(lambda: not any(_running(k) for k in workers), "the orphaned workers to end")
    markers = _markers(out)
    _resume_equals_reference(sim[0], out, ref)
    assert markers >= 3
