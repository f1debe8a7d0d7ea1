"""Fixtures shared by every test folder."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
RIG_YAML = REPO / "config" / "rig.yaml"


@pytest.fixture(scope="session")
def repo() -> Path:
    return REPO


@pytest.fixture(scope="session")
def rig_text() -> str:
    return RIG_YAML.read_text()


@pytest.fixture(scope="session")
def rig():
    """The rig description as shipped (config/rig.yaml), loaded once: the one rig fixture of the suite."""
    from platform_tools.rig import load_rig
    return load_rig()


def bench_module(name: str):
    """bench/<name>.py imported as a module, with this process's environment and import path left as they were
    (a bench pins thread counts and puts bench/ on the path when imported)."""
    import importlib.util
    saved_env, saved_path = dict(os.environ), list(sys.path)
    try:
        spec = importlib.util.spec_from_file_location(f"{name}_under_test", REPO / "bench" / f"{name}.py")
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        return mod
    finally:
        os.environ.clear()
        os.environ.update(saved_env)
        sys.path[:] = saved_path


def run_tool(module: str, *args: str, cwd: Path | None = None, timeout: float = 120) -> subprocess.CompletedProcess:
    """Run a console script of this project as a user would (a fresh process), capturing its output."""
    env = dict(os.environ, COLUMNS="120")
    return subprocess.run([sys.executable, "-m", module, *args], cwd=cwd or REPO, env=env,
                          capture_output=True, text=True, timeout=timeout)


@pytest.fixture
def platform_tools():
    return lambda *args, **kw: run_tool("platform_tools.cli.main", *args, **kw)


@pytest.fixture
def calibrate():
    return lambda *args, **kw: run_tool("calibration.cli", *args, **kw)
