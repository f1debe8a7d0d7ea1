"""Benchmark of the CAD build: `export all` cold (empty cache) and warm (unchanged parameters and
code), `check`, and an `export all` after one parameter change (only the affected parts rebuild).

    .venv/bin/python bench/bench_cad.py

Targets (issue 3): cold export all <= 120 s, warm <= 10 s on 2 cores. Prints one line per run and the
ratios; each run is a fresh process (imports included), as a user runs it.
"""
from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def run(args: list[str], cache: Path, out: Path) -> float:
    env = {**os.environ, "RGBT_CAD_CACHE": str(cache)}
    t0 = time.perf_counter()
    r = subprocess.run([sys.executable, "cad/build.py", *args], cwd=REPO, env=env,
                       stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    dt = time.perf_counter() - t0
    if r.returncode not in (0, 1):
        raise SystemExit(f"bench: {' '.join(args)} failed: {r.stderr.strip()}")
    return dt


def main() -> int:
    with tempfile.TemporaryDirectory(prefix="bench_cad_") as tmp:
        cache, out = Path(tmp) / "cache", Path(tmp) / "out"
        export_all = ["export", "all", "--out", str(out), "-q"]
        cold = run(export_all, cache, out)
        warm = run(export_all, cache, out)
        check = run(["check", "-q"], cache, out)
        changed = run(export_all + ["--set", "enclosure.handles.clearance_mm=40"], cache, out)
        nocache = run(["export", "STEP", "--out", str(out), "-q", "--no-cache"], cache, out)
    rows = [("export all, cold (empty cache)", cold, 120.0), ("export all, warm (unchanged)", warm, 10.0),
            ("check (parts cached)", check, None), ("export all, one handle value changed", changed, None),
            ("export STEP, --no-cache", nocache, None)]
    print(f"{'run':42s} {'seconds':>8s}  target")
    for name, t, target in rows:
        print(f"{name:42s} {t:8.2f}  " + (f"<= {target:g} s {'ok' if t <= target else 'MISSED'}" if target else ""))
    print(f"warm / cold export all:          {warm / cold:.2f}")
    print(f"changed-one-value / cold:        {changed / cold:.2f}")
    print(f"check / warm export all:         {check / warm:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
