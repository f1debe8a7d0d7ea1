"""Check a rendered firmware folder: each check runs a real validator where one is installed
(docker-compose, shellcheck, systemd-analyze) and reports *skipped*, never *passed*, where none is.
"""
from __future__ import annotations

import configparser
import re
import shutil
import subprocess
from pathlib import Path

import yaml

from ..checks import FAILED, OK, SKIPPED, Check
from ..rig import Rig
from .context import build_context
from .launch_stub import Node, load_launch_file



def _run(argv: list[str], cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run(argv, cwd=cwd, capture_output=True, text=True, timeout=60)


def _first_lines(text: str, n: int = 3) -> str:
    lines = [ln for ln in text.strip().splitlines() if ln.strip()]
    return " | ".join(lines[:n]) + (" ..." if len(lines) > n else "")


# ----------------------------------------------------------------------------- compose
def compose_validator() -> list[str] | None:
    """`docker compose` (v2 plugin) when present, else Debian's `docker-compose`, else None."""
    if shutil.which("docker") and subprocess.run(["docker", "compose", "version"], capture_output=True).returncode == 0:
        return ["docker", "compose"]
    if shutil.which("docker-compose"):
        return ["docker-compose"]
    return None


def check_compose_valid(folder: Path) -> Check:
    tool = compose_validator()
    if tool is None:
        return Check("compose valid", SKIPPED, "neither `docker compose` nor `docker-compose` is installed")
    r = _run(tool + ["-f", "compose.yaml", "config", "-q"], folder)
    if r.returncode != 0:
        return Check("compose valid", FAILED, f"{' '.join(tool)} config: {_first_lines(r.stderr + r.stdout)}")
    return Check("compose valid", OK, f"{' '.join(tool)} config accepts compose.yaml")


def _seconds(value) -> float:
    m = re.fullmatch(r"(\d+(?:\.\d+)?)(ms|s|m|h)?", str(value).strip())
    if not m:
        raise ValueError(f"not a duration: {value!r}")
    return float(m.group(1)) * {"ms": 1e-3, "s": 1, None: 1, "m": 60, "h": 3600}[m.group(2)]


def check_compose_matches_rig(folder: Path, rig: Rig) -> Check:
    """What the compose file must say for this rig: the stop grace, devices, the data drive."""
    doc = yaml.safe_load((folder / "compose.yaml").read_text())
    ctx = build_context(rig)
    services = doc.get("services", {})
    problems = []
    rec = services.get("recorder", {})
    grace = _seconds(rec.get("stop_grace_period", "10s"))
    if grace < ctx["stop"]["recorder_s"]:
        problems.append(f"recorder stop_grace_period {grace:g} s < the recorder's own stop budget "
                        f"{ctx['stop']['recorder_s']:g} s")
    devices = {d.split(":")[0] for d in rec.get("devices", [])}
    for chip in rig.desc.on_device.gpio_chips:
        if chip not in devices:
            problems.append(f"recorder lacks GPIO device {chip}")
    mount = rig.desc.recording.data_mount
    if not any(str(v).split(":")[0] == mount for v in rec.get("volumes", [])):
        problems.append(f"recorder does not mount the data drive {mount}")
    for t in ctx["thermal"]:
        devs = {d.split(":")[0] for d in services.get(t["name"], {}).get("devices", [])}
        if t["devices"]["video"] not in devs:
            problems.append(f"service {t['name']} lacks {t['devices']['video']}")
    for name, svc in services.items():
        if svc.get("restart") not in ("always", "unless-stopped", "on-failure"):
            problems.append(f"service {name} has no restart policy")
    if problems:
        return Check("compose matches rig", FAILED, "; ".join(problems))
    return Check("compose matches rig", OK,
                       f"{len(services)} services; recorder stop grace {grace:g} s; devices and data drive mapped")


# ----------------------------------------------------------------------------- shell
def check_shellcheck(folder: Path) -> Check:
    scripts = sorted((folder / "bin").glob("*.sh"))
    if not shutil.which("shellcheck"):
        return Check("shellcheck", SKIPPED, "shellcheck is not installed")
    r = _run(["shellcheck", "--format=gcc", *map(str, scripts)], folder)
    if r.returncode != 0:
        return Check("shellcheck", FAILED, _first_lines(r.stdout + r.stderr))
    return Check("shellcheck", OK, f"{len(scripts)} scripts clean")


# ----------------------------------------------------------------------------- launch and parameters
def _params_file(folder: Path, path: str) -> Path:
    return folder / "config" / Path(path).name


def check_params(folder: Path) -> Check:
    bad = []
    files = sorted((folder / "config").glob("*.yaml"))
    for f in files:
        if f.name == "rig.yaml":
            continue
        try:
            doc = yaml.safe_load(f.read_text())
            if not isinstance(doc.get("/**", {}).get("ros__parameters"), dict):
                bad.append(f"{f.name}: no /**: ros__parameters mapping")
        except (yaml.YAMLError, AttributeError) as exc:
            bad.append(f"{f.name}: {exc}")
    if bad:
        return Check("parameter files", FAILED, "; ".join(bad))
    return Check("parameter files", OK, f"{len(files) - 1} ROS 2 parameter files parse")


def _launched_nodes(folder: Path) -> list[Node]:
    nodes: list[Node] = []
    zed = load_launch_file(folder / "launch" / "zed.launch.py")
    nodes += [e for e in zed.entities if isinstance(e, Node)]
    thermal = load_launch_file(folder / "launch" / "thermal.launch.py")
    for side in ("left", "right"):
        for e in thermal.entities:
            if hasattr(e, "run"):
                nodes += e.run({"side": side})
    return nodes


def check_launch(folder: Path, rig: Rig) -> Check:
    try:
        nodes = _launched_nodes(folder)
    except Exception as exc:  # a generated launch file that does not import is the failure reported
        return Check("launch files", FAILED, f"{type(exc).__name__}: {exc}")
    problems = []
    ctx = build_context(rig)
    for t in ctx["thermal"]:
        cam = [n for n in nodes if n.kwargs.get("name") == t["name"]]
        if len(cam) != 1:
            problems.append(f"{t['name']}: {len(cam)} nodes")
            continue
        params = yaml.safe_load(_params_file(folder, cam[0].kwargs["parameters"][0]).read_text())
        p = params["/**"]["ros__parameters"]
        if p.get("video_device") != t["devices"]["video"] or p.get("frame_id") != t["frame_id"]:
            problems.append(f"{t['name']}: parameters do not name {t['devices']['video']} / {t['frame_id']}")
        if (("image_raw", t["topic"]) not in cam[0].kwargs.get("remappings", [])):
            problems.append(f"{t['name']}: image not remapped to {t['topic']}")
    tfs = [n for n in nodes if n.kwargs.get("executable") == "static_transform_publisher"]
    if len(tfs) != len(ctx["static_tfs"]):
        problems.append(f"{len(tfs)} static transforms, expected {len(ctx['static_tfs'])}")
    if problems:
        return Check("launch files", FAILED, "; ".join(problems))
    return Check("launch files", OK, f"import and build {len(nodes)} nodes ({len(tfs)} static transforms)")


# ----------------------------------------------------------------------------- systemd, udev
def check_unit(folder: Path, rig: Rig) -> Check:
    path = folder / "systemd" / "rgbt-rig.service"
    parser = configparser.ConfigParser(strict=True, interpolation=None)
    parser.optionxform = str
    problems = []
    try:
        parser.read_string(path.read_text())
    except configparser.Error as exc:
        return Check("systemd unit", FAILED, f"{path.name}: {exc}")
    unit, service = parser["Unit"], parser["Service"]
    if unit.get("RequiresMountsFor") != rig.desc.recording.data_mount:
        problems.append(f"RequiresMountsFor is not the data mount {rig.desc.recording.data_mount}")
    if "zed_x_daemon.service" not in unit.get("After", ""):
        problems.append("not ordered after zed_x_daemon.service")
    if _seconds(service.get("TimeoutStopSec", "0")) <= build_context(rig)["stop"]["container_s"]:
        problems.append("TimeoutStopSec does not leave the recorder container its stop grace period")
    if shutil.which("systemd-analyze"):
        r = _run(["systemd-analyze", "verify", str(path)], folder)
        # only syntax problems: the Orin's units and paths do not exist on this machine
        syntax = [ln for ln in (r.stderr + r.stdout).splitlines() if re.match(rf"{re.escape(str(path))}:\d+:", ln)]
        problems += syntax
    if problems:
        return Check("systemd unit", FAILED, "; ".join(problems))
    tool = " (and systemd-analyze verify)" if shutil.which("systemd-analyze") else ""
    return Check("systemd unit", OK, f"starts after the data drive and the ZED X daemon{tool}")


_UDEV_PAIR = re.compile(r'\s*([A-Za-z_]+(?:\{[^}]+\})?)\s*(==|!=|\+=|-=|:=|=)\s*"([^"]*)"\s*(?:,|$)')


def parse_udev_line(line: str) -> list[tuple[str, str, str]]:
    """A rules line as (key, operator, value) pairs; ValueError when it does not parse."""
    pairs, pos = [], 0
    while pos < len(line):
        m = _UDEV_PAIR.match(line, pos)
        if not m:
            raise ValueError(f"cannot parse at column {pos + 1}: {line[pos:pos + 30]!r}")
        pairs.append(m.groups())
        pos = m.end()
    return pairs


def check_udev(folder: Path, rig: Rig) -> Check:
    path = folder / "udev" / "99-rgbt-boson.rules"
    names, problems = [], []
    for n, line in enumerate(path.read_text().splitlines(), 1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        try:
            pairs = parse_udev_line(line)
        except ValueError as exc:
            problems.append(f"{path.name}:{n}: {exc}")
            continue
        names += [v for k, op, v in pairs if k == "SYMLINK"]
    expected = [p[5:] for side in ("left", "right") if getattr(rig.desc.sensors.thermal, side).serial
                for p in build_context(rig)["thermal"][0 if side == "left" else 1]["devices"].values()]
    if sorted(names) != sorted(expected):
        problems.append(f"symlinks {sorted(names)}, expected {sorted(expected)}")
    if problems:
        return Check("udev rules", FAILED, "; ".join(problems))
    return Check("udev rules", OK, f"{len(names)} stable names" +
                       ("" if len(expected) == 4 else " (serial numbers not set yet)"))


def run_checks(folder: Path, rig: Rig) -> list[Check]:
    folder = Path(folder).resolve()   # validators run inside the folder: no relative path may leak in
    return [check_compose_valid(folder), check_compose_matches_rig(folder, rig), check_shellcheck(folder),
            check_params(folder), check_launch(folder, rig), check_unit(folder, rig), check_udev(folder, rig)]
