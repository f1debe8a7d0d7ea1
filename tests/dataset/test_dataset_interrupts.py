"""The export's process pool (engines.Pool) stopped whole by a SIGTERM landing on any line its main thread runs in
concurrent.futures (tests/dataset/interrupt_probe.py); a SIGTERM in concurrent.futures.wait did not stop it (CI,
stop 38: an export that SIGTERM never ended). platform_tools.rig.interrupts' own tests: tests/rig/test_interrupts.py."""
from __future__ import annotations

import json
import subprocess
import sys

import pytest

from tests.conftest import REPO


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
