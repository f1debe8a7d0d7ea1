"""Clean stops of a real `platform_tools export` process with a pool of 2 workers: Ctrl-C (SIGINT to the process
group, as a terminal sends it), SIGTERM, and a SIGKILL of the parent; each with spawned and with forked workers
(engines.START_ENV, inherited by the export process; forked is the default on Linux). Workers are found by pid (the
parent's children in /proc) and checked gone, not timed; the interrupted export is then resumed with the same
command and must equal, file for file, an uninterrupted export made with that command: byte for byte, except that a
PNG need only hold the same scanlines (ISA-L's deflate may encode them with other Huffman tables:
tests/dataset/pngsame.py)."""
from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from platform_tools.dataset.engines import START_ENV
from tests.conftest import REPO
from tests.dataset.pngsame import same_file

pytestmark = [pytest.mark.slow, pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")]

#: a bound on waiting for the export to reach a state; reaching it later fails the test, sooner proves nothing
WAIT_S = 300
#: the workers' start methods the stop scenarios run with
METHODS = ("spawn", "fork")


def _cmd(sim_dir: Path, out: Path) -> list[str]:
    # every pair (30 Hz), one sample per chunk: many chunks, so a stop lands in the middle; the rig description is
    # the copy the reference took (beside ``out``), so an edit of config/rig.yaml while the tests run (its hash is in
    # every marker) does not tell the runs apart
    return [sys.executable, "-m", "platform_tools.cli.main", "export", str(sim_dir), "--out", str(out),
            "--rate", "30", "--workers", "2", "--chunk-size", "1", "--rig", str(out.parent / "rig.yaml"), "-q"]


def _children(pid: int) -> dict[int, str]:
    """pid -> command line of the live processes whose parent is ``pid``."""
    out = {}
    for d in Path("/proc").iterdir():
        if not d.name.isdigit():
            continue
        try:
            stat = (d / "stat").read_text()
            cmdline = (d / "cmdline").read_bytes().replace(b"\0", b" ").decode()
        except OSError:
            continue
        fields = stat.rsplit(")", 1)[1].split()
        if int(fields[1]) == pid and fields[0] != "Z":
            out[int(d.name)] = cmdline
    return out


def _running(pid: int) -> bool:
    """Alive and not a zombie (an orphan reparented to a PID 1 that does not reap stays a zombie: not running)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def _wait(cond, what: str) -> None:
    deadline = time.monotonic() + WAIT_S
    while not cond():
        if time.monotonic() > deadline:
            pytest.fail(f"gave up waiting for {what}")
        time.sleep(0.05)


def _tree(out: Path) -> dict[str, bytes]:
    return {str(p.relative_to(out)): p.read_bytes() for p in sorted(out.rglob("*")) if p.is_file()}


def _markers(out: Path) -> int:
    return len(list((out / ".chunks").glob("*.json"))) if (out / ".chunks").is_dir() else 0


@pytest.fixture(scope="module")
def reference(sim, rig_text, tmp_path_factory):
    """An uninterrupted export, made where the interrupted ones go (the card holds the command line), kept aside;
    with the default workers, whichever method the interrupted runs use."""
    base = tmp_path_factory.mktemp("stops")
    (base / "rig.yaml").write_text(rig_text)           # config/rig.yaml as the session read it
    out = base / "ds"
    env = {k: v for k, v in os.environ.items() if k != START_ENV}
    r = subprocess.run(_cmd(sim[0], out), cwd=REPO, capture_output=True, text=True, timeout=1200, env=env)
    assert r.returncode == 0, r.stderr
    shutil.move(out, base / "reference")
    return base, _tree(base / "reference")


def _as_a_foreground_job() -> None:
    """SIGINT at its default, as a terminal's foreground job has it. A process inherits an ignored SIGINT, and a
    shell without job control starts its background jobs (`cmd &` in a script: how CI and nohup run the tests) with
    SIGINT ignored; Python then leaves it ignored, and the export rightly does not see Ctrl-C (it finished, exit 0:
    the test's one intermittent failure)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _start(sim_dir: Path, out: Path) -> subprocess.Popen:
    shutil.rmtree(out, ignore_errors=True)
    p = subprocess.Popen(_cmd(sim_dir, out), cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         start_new_session=True,        # its own process group, as a shell job
                         preexec_fn=_as_a_foreground_job)
    _wait(lambda: _markers(out) >= 3 or p.poll() is not None, "three finished chunks")
    assert p.poll() is None, p.stderr.read()
    return p


@pytest.fixture(params=METHODS)
def method(request, monkeypatch):
    """The export processes started in the test start their workers this way (the variable is inherited)."""
    monkeypatch.setenv(START_ENV, request.param)
    return request.param


def _workers(p: subprocess.Popen, method: str) -> tuple[list[int], list[int]]:
    """(the pool's worker pids, every child's pid), checked to be what ``method`` makes: spawned, two fresh
    interpreters running multiprocessing's spawn_main beside its resource tracker (the semaphores of a spawning
    context are named, and the tracker unlinks them); forked, exactly two children carrying the parent's own
    command line and no tracker (a forking context's semaphores are unlinked at once)."""
    kids = _children(p.pid)
    trackers = [k for k, cmd in kids.items() if "resource_tracker" in cmd]
    workers = [k for k in kids if k not in trackers]
    assert len(workers) == 2, kids
    if method == "spawn":
        assert len(trackers) == 1 and all("spawn_main" in kids[w] for w in workers), kids
    else:
        own = Path(f"/proc/{p.pid}/cmdline").read_bytes().replace(b"\0", b" ").decode()
        assert trackers == [] and all(kids[w] == own for w in workers), kids
    return workers, list(kids)


def _resume_equals_reference(sim_dir: Path, out: Path, reference: dict) -> None:
    manifest = json.loads((out / "export.json").read_text())
    assert manifest["status"] == "running" and _markers(out) < manifest["chunks"]   # stopped midway
    assert not (out / "index.csv").exists() and not (out / "README.md").exists()
    before, markers = _tree(out), {m.stem for m in (out / ".chunks").glob("*.json")}
    r = subprocess.run(_cmd(sim_dir, out)[:-1] + ["--json"], cwd=REPO, capture_output=True, text=True, timeout=1200)
    assert r.returncode == 0, r.stderr
    s = json.loads(r.stdout)
    assert s["resumed"] and 0 < s["chunks_run"] < s["chunks"]
    got = _tree(out)
    assert sorted(got) == sorted(reference)
    differ = [k for k in got if not same_file(k, got[k], reference[k])]   # PNGs: the same scanlines (pngsame.py)
    assert differ == [], _explain(differ, got, reference, before, markers)


def _explain(differ: list[str], got: dict, reference: dict, before: dict, markers: set[str]) -> str:
    """What a mismatch is: for each file, whether the interrupted run had left it (and the resume kept it), whether
    its chunk had a marker before the resume, and how far its pixels are from the reference's."""
    import cv2
    import numpy as np
    lines = []
    for k in differ:
        line = f"{k}: {len(got[k])} bytes against {len(reference[k])}"
        if k in before:
            line += ", left by the interrupted run" + (" and kept by the resume" if before[k] == got[k] else
                                                      ", rewritten by the resume")
        if k.endswith(".png"):
            sample = int(Path(k).stem)
            line += f", its chunk's marker {'was' if any(m.endswith(f'-{sample:05d}') for m in markers) else 'was not'}"
            line += " there before the resume"
            a, b = (cv2.imdecode(np.frombuffer(x, np.uint8), cv2.IMREAD_UNCHANGED) for x in (got[k], reference[k]))
            if a is None or b is None or a.shape != b.shape:
                line += f"; decodes: {None if a is None else a.shape} against {None if b is None else b.shape}"
            else:
                d = np.abs(a.astype(np.int64) - b.astype(np.int64))
                line += f"; {int(np.count_nonzero(d))} pixels differ, by up to {int(d.max())}"
        lines.append(line)
    return "\n".join(lines)


@pytest.mark.parametrize("how", ["ctrl-c", "sigterm"])
def test_an_interrupt_stops_every_worker_and_the_export_resumes_identical(sim, reference, method, how):
    base, ref = reference
    out = base / "ds"
    p = _start(sim[0], out)
    workers, kids = _workers(p, method)
    if how == "ctrl-c":
        os.killpg(p.pid, signal.SIGINT)           # the whole foreground group, workers included
    else:
        os.kill(p.pid, signal.SIGTERM)
    _, err = p.communicate(timeout=WAIT_S)
    assert p.returncode == 130, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "interrupted" in lines[0] and str(out) in lines[0], err   # no worker traceback
    # the parent stopped and reaped its workers before it exited; at most the resource tracker (spawn) is still ending
    assert [w for w in workers if _running(w)] == []
    _wait(lambda: not any(_running(k) for k in kids), "the resource tracker to end")
    assert not list(out.rglob("*.tmp"))                      # what the stopped workers were writing is gone
    _resume_equals_reference(sim[0], out, ref)


def test_workers_end_when_the_parent_is_killed(sim, reference, method):
    base, ref = reference
    out = base / "ds"
    p = _start(sim[0], out)
    _, kids = _workers(p, method)
    p.kill()
    p.wait()
    # without PR_SET_PDEATHSIG the orphans kept encoding for over ten minutes; with it they die at once
    _wait(lambda: not any(_running(k) for k in kids), "the orphaned workers to end")
    markers = _markers(out)
    _resume_equals_reference(sim[0], out, ref)
    assert markers >= 3
