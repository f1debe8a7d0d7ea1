"""Simulated recordings shared by the dataset tests (small images: these are about timing and geometry)."""
from __future__ import annotations

import json

import pytest

from platform_tools.sim.timeline import SimParams
from platform_tools.sim.writer import simulate


@pytest.fixture(scope="session")
def sim(tmp_path_factory, rig):
    """A 6 s recording: drops, FFC on both Bosons, a clock step; images at 0.15 of full size."""
    out = tmp_path_factory.mktemp("sim") / "rec"
    simulate(rig, out, SimParams(6.0, seed=5, drop_probability=0.02), scale=0.15)
    return out, json.loads((out / "truth.json").read_text())
