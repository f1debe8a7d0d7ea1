"""Check a rendered firmware folder: each check runs a real validator where one is installed
(docker-compose, shellcheck, systemd-analyze) and reports *skipped*, never *passed*, where none is.
"""
from __future__ import annotations

import configparser
import io
import re
import shlex
import shutil
import subprocess
from pathlib import Path, PurePosixPath

import yaml

from platform_tools.rig.checks import FAILED, OK, SKIPPED, Check
from platform_tools.rig import Rig
from platform_tools.rig.yamlsource import safe_load
from firmware import budget, health_topics, privilege, v4l2
from firmware.context import L4T_RELEASES, build_context
from firmware.launch_stub import ExecuteProcess, Node, load_launch_file



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
    doc = safe_load((folder / "compose.yaml").read_text())
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
    files = sorted(f for f in (folder / "config").glob("*.yaml") if not f.name.endswith("_camera_info.yaml"))
    for f in files:
        if f.name == "rig.yaml":
            continue
        try:
            doc = safe_load(f.read_text())
            if not isinstance(doc.get("/**", {}).get("ros__parameters"), dict):
                bad.append(f"{f.name}: no /**: ros__parameters mapping")
        except (yaml.YAMLError, AttributeError) as exc:
            bad.append(f"{f.name}: {exc}")
    if bad:
        return Check("parameter files", FAILED, "; ".join(bad))
    return Check("parameter files", OK, f"{len(files) - 1} ROS 2 parameter files parse")


def _launched_nodes(folder: Path) -> list:
    """Every Node and ExecuteProcess the launch files start (the thermal one for both sides)."""
    nodes: list = []
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
    procs = [n for n in nodes if isinstance(n, ExecuteProcess)]
    nodes = [n for n in nodes if isinstance(n, Node)]
    for t in ctx["thermal"]:
        cam = [n for n in nodes if n.kwargs.get("name") == t["name"]]
        if len(cam) != 1:
            problems.append(f"{t['name']}: {len(cam)} nodes")
            continue
        params = safe_load(_params_file(folder, cam[0].kwargs["parameters"][0]).read_text())
        p = params["/**"]["ros__parameters"]
        if p.get("video_device") != t["devices"]["video"] or p.get("frame_id") != t["frame_id"]:
            problems.append(f"{t['name']}: parameters do not name {t['devices']['video']} / {t['frame_id']}")
        if (("image_raw", t["topic"]) not in cam[0].kwargs.get("remappings", [])):
            problems.append(f"{t['name']}: image not remapped to {t['topic']}")
        if t["telemetry_rows"]:
            pub = [p for p in procs if p.kwargs.get("name") == f"{t['name']}_status"]
            cmd = pub[0].kwargs.get("cmd", []) if len(pub) == 1 else []
            want = [f"image_topic:={t['topic']}", f"status_topic:={t['status_topic']}",
                    f"telemetry_rows:={t['telemetry_rows']}"]
            if "firmware.device.ffc_node" not in cmd or any(w not in cmd for w in want):
                problems.append(f"{t['name']}: no FFC status publisher from {t['topic']} to {t['status_topic']}")
    tfs = [n for n in nodes if n.kwargs.get("executable") == "static_transform_publisher"]
    if len(tfs) != len(ctx["static_tfs"]):
        problems.append(f"{len(tfs)} static transforms, expected {len(ctx['static_tfs'])}")
    if problems:
        return Check("launch files", FAILED, "; ".join(problems))
    return Check("launch files", OK, f"import and build {len(nodes)} nodes ({len(tfs)} static transforms) "
                                     f"and {len(procs)} FFC status publishers")


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


# ----------------------------------------------------------------------------- Dockerfiles
def _parse_dockerfile(text: str):
    from dockerfile_parse import DockerfileParser
    return DockerfileParser(fileobj=io.BytesIO(text.encode()))


def _copy_sources(value: str) -> list[str]:
    """The sources of a COPY / ADD value (shell or JSON form; flags such as --chown dropped)."""
    value = value.strip()
    if value.startswith("["):
        import json
        parts = json.loads(value)
    else:
        parts = shlex.split(value)
    parts = [p for p in parts if not p.startswith("--")]
    return parts[:-1]


def _base_ok(name: str, base: str, images: dict) -> str | None:
    """None when ``base`` is an image for the Orin's JetPack, else why not."""
    repo, _, tag = base.split("@", 1)[0].partition(":")    # a digest (on_device.base_images) pins the tag
    release = images["release"]
    if repo.startswith("nvcr.io/nvidia/l4t-"):
        if not re.fullmatch(rf"{release}\.\d+(\.\d+)?", tag):
            return f"{base} is not L4T {release} (the image tags say l4t-{release})"
        return None
    if name == "zed":
        return f"{base}: the ZED SDK needs CUDA: expected an NVIDIA L4T {release} image (nvcr.io/nvidia/l4t-*)"
    if repo == "ros":
        want = f"{images['ros_distro']}-ros-base-{images['ubuntu']}"
        if not tag.startswith(f"{images['ros_distro']}-") or not tag.endswith(f"-{images['ubuntu']}"):
            return f"{base}: expected a ROS {images['ros_distro']} image on Ubuntu {images['ubuntu']} " \
                   f"(the Ubuntu of L4T {release}), e.g. ros:{want}"
        return None
    return f"{base} is neither an NVIDIA L4T image (nvcr.io/nvidia/l4t-*) nor an official ROS image"


def check_dockerfiles(folder: Path, rig: Rig) -> Check:
    """The Dockerfiles parse (dockerfile-parse), start from an L4T or ROS image for the Orin's JetPack,
    COPY only what their build context holds, and every compose service's image is built by one."""
    try:
        import dockerfile_parse  # noqa: F401
    except ImportError:
        return Check("dockerfiles", SKIPPED, "dockerfile-parse is not installed (pip install dockerfile-parse)")
    images = build_context(rig)["images"]
    doc = safe_load((folder / "compose.yaml").read_text())
    problems, built = [], {}
    for svc_name, svc in (doc.get("services") or {}).items():
        build = svc.get("build")
        if not build:
            problems.append(f"service {svc_name}: image {svc.get('image')} has no build section")
            continue
        if isinstance(build, str):
            build = {"context": build}
        context = (folder / build.get("context", ".")).resolve()
        dockerfile = context / build.get("dockerfile", "Dockerfile")
        if folder not in context.parents and context != folder:
            problems.append(f"service {svc_name}: build context {build.get('context')} is outside the folder")
            continue
        if not dockerfile.is_file():
            problems.append(f"service {svc_name}: no {dockerfile.relative_to(folder)}")
            continue
        if svc.get("image") not in images["tags"].values():
            problems.append(f"service {svc_name}: image {svc.get('image')} is not one of on_device.images")
        built.setdefault(dockerfile, (context, svc_name, svc.get("image")))
    tags_built = {tag: df for df, (_, _, tag) in built.items()}
    for name, tag in images["tags"].items():
        if tag not in tags_built:
            problems.append(f"on_device.images.{name} ({tag}) is built by no service")
        elif tags_built[tag] != (folder / images["dockerfiles"][name]).resolve():
            problems.append(f"{tag} is not built from {images['dockerfiles'][name]}")
    for dockerfile, (context, svc_name, tag) in sorted(built.items()):
        rel = dockerfile.relative_to(folder)
        try:
            parser = _parse_dockerfile(dockerfile.read_text())
            structure = parser.structure
            bases = parser.parent_images
        except Exception as exc:  # a Dockerfile the parser rejects is the failure reported
            problems.append(f"{rel}: does not parse ({type(exc).__name__}: {exc})")
            continue
        instructions = [i["instruction"] for i in structure if i["instruction"] != "COMMENT"]
        if not bases or "FROM" not in instructions:
            problems.append(f"{rel}: no FROM")
        if instructions and instructions[0] not in ("FROM", "ARG"):
            problems.append(f"{rel}: starts with {instructions[0]}, not FROM or ARG")
        for b in bases:
            if "$" in b:
                problems.append(f"{rel}: base image {b} has an unresolved build argument")
                continue
            why = _base_ok(next((n for n, t in images["tags"].items() if t == tag), ""), b, images)
            if why:
                problems.append(f"{rel}: {why}")
        for ins in structure:
            if ins["instruction"] not in ("COPY", "ADD") or "--from=" in ins["value"]:
                continue
            for src in _copy_sources(ins["value"]):
                if re.match(r"[a-z]+://", src):
                    continue
                path = PurePosixPath(src)
                if path.is_absolute() or ".." in path.parts:
                    problems.append(f"{rel}:{ins['startline'] + 1}: COPY {src} leaves the build context")
                elif not any(context.glob(src)) and not (context / src).exists():
                    problems.append(f"{rel}:{ins['startline'] + 1}: COPY {src}: not in the build context "
                                    f"{context.relative_to(folder)}/")
    if problems:
        return Check("dockerfiles", FAILED, "; ".join(problems))
    return Check("dockerfiles", OK, f"{len(built)} Dockerfiles parse (dockerfile-parse); bases for L4T "
                                    f"{images['release']} / ROS {images['ros_distro']}; COPY sources in their "
                                    f"contexts; every compose image built")


def check_device_install(folder: Path, rig: Rig) -> Check:
    """The pyproject.toml the images install declares only console scripts whose module is in the source
    they install: a `platform_tools` or `calibrate` script there would be installed and fail on import."""
    import tomllib
    images = build_context(rig)["images"]
    src = folder / images["dir"] / images["source_dir"]
    try:
        project = tomllib.loads((src / "pyproject.toml").read_text())
    except (OSError, tomllib.TOMLDecodeError) as exc:
        return Check("device install", FAILED, f"{src.relative_to(folder)}/pyproject.toml: {exc}")
    scripts = project.get("project", {}).get("scripts", {})
    bad = []
    for name, entry in scripts.items():
        module = entry.split(":", 1)[0].split(".")
        if not ((src.joinpath(*module).with_suffix(".py")).is_file() or (src.joinpath(*module, "__init__.py")).is_file()):
            bad.append(f"console script {name} = {entry}: {'.'.join(module)} is not in the images' source")
    if project.get("project", {}).get("dependencies"):
        bad.append("dependencies are declared: the images install with --no-deps from Ubuntu and pip (Dockerfiles)")
    if bad:
        return Check("device install", FAILED, "; ".join(bad))
    return Check("device install", OK, f"console scripts {', '.join(scripts) or 'none'}, each in the images' source")


def run_checks(folder: Path, rig: Rig) -> list[Check]:
    folder = Path(folder).resolve()   # validators run inside the folder: no relative path may leak in
    return [check_compose_valid(folder), check_compose_matches_rig(folder, rig), check_shellcheck(folder),
            check_params(folder), check_launch(folder, rig), check_unit(folder, rig), check_udev(folder, rig),
            check_dockerfiles(folder, rig), check_device_install(folder, rig), *privilege.run(folder, rig),
            budget.check_budget(folder, rig), health_topics.check_health_topics(folder, rig),
            budget.check_chunk_crcs(rig),
            v4l2.check_controls(folder, rig, [t["name"] for t in build_context(rig)["thermal"]])]
