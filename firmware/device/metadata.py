"""The metadata JSON of a recording (``recording.json`` next to its bag): what was recorded, with
what, when, how it stopped and what went wrong. Written when the recording starts (status
``recording``) and rewritten when it ends, always atomically: after a power loss the file still
says when the recording started and that it never finished."""
from __future__ import annotations

import datetime as dt
import hashlib
import json
import subprocess
from importlib import metadata as importlib_metadata
from pathlib import Path

from platform_tools.rig import atomic
from platform_tools.rig import Rig

FILE_NAME = "recording.json"
REPO = Path(__file__).resolve().parents[2]


def utc_now() -> str:
    return dt.datetime.now(dt.timezone.utc).isoformat(timespec="milliseconds")


def software_version() -> str:
    try:
        version = importlib_metadata.version("rgbt-rig")
    except importlib_metadata.PackageNotFoundError:
        version = "unknown"
    try:
        r = subprocess.run(["git", "-C", str(REPO), "describe", "--always", "--dirty"], capture_output=True,
                           text=True, timeout=5)
        if r.returncode == 0 and r.stdout.strip():
            version += f"+git.{r.stdout.strip()}"
    except (OSError, subprocess.TimeoutExpired):
        pass
    return version


def file_sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def new_metadata(rig: Rig, name: str, cameras: dict, calibration: Path | None, recorder: dict) -> dict:
    thermal = rig.desc.sensors.thermal
    cams = {side: {"serial": getattr(thermal, side).serial, "firmware": None} | cameras.get(side, {})
            for side in ("left", "right")}
    return {
        "name": name,
        "status": "recording",
        "rig": {"name": rig.desc.name, "hash": rig.hash, "file": str(rig.path), "overrides": list(rig.overrides)},
        "calibration": ({"file": str(calibration), "sha256": file_sha256(calibration)} if calibration else None),
        "cameras": cams,
        "software": software_version(),
        "recorder": recorder,
        "started_utc": utc_now(),
        "stopped_utc": None,
        "duration_s": None,
        "stop": None,
        "files": [],
        "faults": [],
    }


def write(folder: Path, meta: dict) -> Path:
    return atomic.write_text(folder / FILE_NAME, json.dumps(meta, indent=2, default=str) + "\n")


def read(folder: Path) -> dict:
    return json.loads((folder / FILE_NAME).read_text())
