"""Fixtures shared by the calibration tests: small synthetic sets, rendered once per session."""
from __future__ import annotations

import pytest


@pytest.fixture(scope="session")
def synth_set(tmp_path_factory):
    """synth_set(difficulty, n, seed, board=(10, 7), only=None) -> folder with NNN.png, truth.json,
    truth.cameramodel (``only``: just those image indices of the n, as render_dataset renders them)."""
    from calibration.synth import render_dataset
    cache = {}

    def make(difficulty: str = "easy", n: int = 4, seed: int = 0, board=(10, 7), square: float = 0.04, only=None):
        key = (difficulty, n, seed, tuple(board), square, None if only is None else tuple(only))
        if key not in cache:
            out = tmp_path_factory.mktemp(f"synth_{difficulty}") / "set"
            render_dataset(out, n=n, difficulty=difficulty, board=board, square=square, seed=seed,
                           show_progress=False, only=only)
            cache[key] = out
        return cache[key]
    return make
