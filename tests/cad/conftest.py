import fcntl
import os
import pickle

import pytest


@pytest.fixture(scope="session")
def asm(rig):
    from cad.assembly import build
    return build(rig)


def _checks(asm) -> dict:
    from cad.checks import run_checks
    return {r.name: r for r in run_checks(asm)}


@pytest.fixture(scope="session")
def results(asm, tmp_path_factory, worker_id):
    """Every check of cad/checks.py on the default rig, by name: run once per test run (85-100 s on 2 cores). Under
    pytest-xdist the first worker to need them runs them, holding a lock in the run's shared temporary folder, and
    pickles them there; a worker that needs them later reads them (the same rig and code, so the same results)."""
    if worker_id == "master":
        return _checks(asm)
    shared = tmp_path_factory.getbasetemp().parent
    path = shared / "cad_checks.pickle"
    with open(shared / "cad_checks.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if path.is_file():
            return pickle.loads(path.read_bytes())
        got = _checks(asm)
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_bytes(pickle.dumps(got))
        os.replace(tmp, path)
        return got
