"""`make demo`: run the project's main job end to end and say what it made and where.

Each step is a real command, run as a user would run it (its command line is printed first). Every
capability of the project adds its step here; everything is written under the --out folder.
"""
from __future__ import annotations

import argparse
import shlex
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


@dataclass(frozen=True)
class Step:
    title: str
    argv: tuple[str, ...]   # "{out}": the step's output folder; "{build}": the demo's whole output folder
    out: str                # sub-folder of the demo's output folder
    show_output: bool = False  # print what the command prints (a result worth reading in the demo)


def _tool(name: str) -> tuple[str, ...]:
    """A console script of this project, run with the same interpreter as the demo."""
    return (sys.executable, "-m", {"platform_tools": "platform_tools.cli.main",
                                   "calibrate": "calibration.cli"}[name])


STEPS: list[Step] = [
    Step("rig description, resolved, and its sensor frames",
         _tool("platform_tools") + ("rig", "export", "--out", "{out}"), "rig"),
    Step("nominal camera models from the rig description",
         _tool("calibrate") + ("nominal", "--out", "{out}"), "calibration/nominal"),
    Step("CAD: the rig assembly (STEP, GLB), printed parts (STEP, STL), views (SVG, PNG)",
         (sys.executable, "cad/build.py", "export", "all", "--out", "{out}"), "cad"),
    Step("CAD: check the assembly (interference, walls, clearances, fields of view, ...)",
         (sys.executable, "cad/build.py", "check", "--report", "{out}/check_report.txt"), "cad/check"),
    Step("bill of materials: the CAD assembly joined with bom/parts.yaml (csv, md, html; printed parts)",
         (sys.executable, "cad/build.py", "bom", "--out", "{out}"), "bom"),
    Step("assembly guide, BOM, wiring and printing pages with pictures from the CAD model (open index.html)",
         (sys.executable, "cad/build.py", "docs", "--out", "{out}"), "docs"),
    Step("on-device configuration (compose, systemd, udev, ROS 2 launch) from the rig description",
         _tool("platform_tools") + ("firmware", "render", "--out", "{out}"), "firmware"),
    Step("a simulated 5 s recording (MCAP, ROS 2 messages) with its injected faults in truth.json",
         _tool("platform_tools") + ("simulate-rig", "--out", "{out}", "--duration", "5"), "sim"),
    Step("that recording as a dataset: FFC-filtered 1 Hz pairs, 8-bit thermal, RGB registered into each thermal view",
         _tool("platform_tools") + ("export", "{build}/sim", "--out", "{out}", "--workers", "2"), "sim/dataset"),
    Step("two emulated Bosons put in external-sync slave mode (read, diff, apply, verify, trigger check)",
         _tool("platform_tools") + ("boson-emulator", "--serial", "93588", "--serial", "93589", "--trigger",
                                    "--session-out", "{out}", "--run", "boson-config", "--slave",
                                    "--check-trigger", "--set", "sensors.thermal.left.serial=93588",
                                    "--set", "sensors.thermal.right.serial=93589", "--json"), "boson"),
    Step("CAD extrinsics of every camera and the IMU (extrinsics.yaml, Kalibr camchain, URDF, ROS 2 launch, mrcal)",
         _tool("calibrate") + ("extrinsics", "--from-cad", "--out", "{out}"), "calibration/extrinsics"),
    Step("synthetic thermal checkerboard images with ground truth (40 images, 'real' difficulty)",
         _tool("calibrate") + ("synth", "--out", "{out}", "--n", "40", "--difficulty", "real", "--seed", "1"),
         "calibration/synth"),
    Step("thermal intrinsics of that synthetic set (mrcal OPENCV8; all formats, report.html with its verdict)",
         _tool("calibrate") + ("thermal", "--images", "{build}/calibration/synth", "--board", "10x7",
                               "--square", "0.04", "--out", "{out}"), "calibration/thermal"),
    Step("the solved thermal model against the synthetic set's true lens",
         _tool("calibrate") + ("validate", "{build}/calibration/thermal/thermal.cameramodel",
                               "--truth", "{build}/calibration/synth", "--exit-zero"), "calibration/thermal",
         show_output=True),
]


def _display(argv: tuple[str, ...]) -> str:
    """The command as a user types it (console script name instead of python -m)."""
    if len(argv) > 2 and argv[1] == "-m":
        name = {"platform_tools.cli.main": "platform_tools", "calibration.cli": "calibrate"}.get(argv[2], argv[2])
        argv = (name,) + argv[3:]
    return shlex.join(argv)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m platform_tools.demo",
                                     description="Build every output of the project under --out.")
    parser.add_argument("--out", type=Path, default=REPO / "build", help="output folder (default: build/)")
    args = parser.parse_args(argv)
    out = args.out.resolve()
    made: list[tuple[Step, Path, float]] = []
    for i, step in enumerate(STEPS, 1):
        target = out / step.out
        cmd = tuple(a.replace("{out}", str(target)).replace("{build}", str(out)) for a in step.argv)
        print(f"[{i}/{len(STEPS)}] {step.title}\n      $ {_display(cmd)}", flush=True)
        t0 = time.monotonic()
        result = subprocess.run(cmd, cwd=REPO, stdout=None if step.show_output else subprocess.DEVNULL)
        if result.returncode != 0:
            print(f"demo: step {i} failed (exit {result.returncode}): {_display(cmd)}", file=sys.stderr)
            return result.returncode
        made.append((step, target, time.monotonic() - t0))

    print(f"\nWhat the demo made, under {out}:")
    listed: set[Path] = set()
    for step, target, seconds in made:
        if target in listed:  # a later step that reads or checks what an earlier one made
            continue
        listed.add(target)
        files = sorted(p for p in target.rglob("*") if p.is_file())
        size = sum(p.stat().st_size for p in files)
        print(f"  {step.title} ({seconds:.1f} s): {target.relative_to(out)}/  {len(files)} files, {size / 1024:.0f} KiB")
        for p in files[:12]:
            print(f"      {p.relative_to(out)}")
        if len(files) > 12:
            print(f"      ... and {len(files) - 12} more")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
