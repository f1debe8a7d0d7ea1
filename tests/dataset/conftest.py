"""Simulated recordings shared by the dataset tests (small images: these are about timing and geometry)."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from platform_tools.sim.timeline import SimParams
from platform_tools.sim.writer import simulate


@pytest.fixture(scope="session")
def sim(tmp_path_factory, rig):
    """A 6 s recording: drops, FFC on both Bosons, a clock step; images at 0.15 of full size."""
    out = tmp_path_factory.mktemp("sim") / "rec"
    simulate(rig, out, SimParams(6.0, seed=5, drop_probability=0.02), scale=0.15)
    return out, json.loads((out / "truth.json").read_text())


@pytest.fixture(scope="session")
def built(tmp_path_factory) -> Path:
    """A folder holding the export kernels' extension for this machine's key, built by the command the bootstrap
    runs (``python -m platform_tools.dataset.kernels build --dir``), once per test process."""
    import subprocess
    import sys
    from tests.conftest import REPO
    where = tmp_path_factory.mktemp("kernels")
    r = subprocess.run([sys.executable, "-m", "platform_tools.dataset.kernels", "build", "--dir", str(where), "--json"],
                       cwd=REPO, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout + r.stderr
    doc = json.loads(r.stdout)
    assert doc["ok"] and doc["built"] and Path(doc["extension"]).parent == where
    assert [p.name for p in where.iterdir()] == [Path(doc["extension"]).name]      # no build folder left behind
    return where

