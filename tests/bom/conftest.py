"""One BOM per rig variant per session; bad-input tests run the command in process (they fail before CAD)."""
from __future__ import annotations

import csv
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]


def build_py(*args: str, timeout: float = 300) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "cad/build.py", *args], cwd=REPO, capture_output=True, text=True,
                          timeout=timeout)


def read_bom(folder: Path) -> dict[str, dict]:
    with open(folder / "bom.csv", newline="") as f:
        return {row["key"]: row for row in csv.DictReader(f)}


@pytest.fixture(scope="session")
def bom_default(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("bom") / "default"
    r = build_py("bom", "--out", str(out), "-q")
    assert r.returncode == 0, r.stderr
    return out


#: the rig change the tests make: no side handles (8 screws and 8 inserts fewer) and a wider thermal pair
CHANGES = ("--set", "enclosure.handles.sides=false", "--set", "sensors.thermal.baseline_mm=130")


@pytest.fixture(scope="session")
def bom_changed(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("bom") / "changed"
    r = build_py("bom", "--out", str(out), "-q", *CHANGES)
    assert r.returncode == 0, r.stderr
    return out
