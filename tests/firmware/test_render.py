"""`platform_tools firmware render`: the files follow the rig description, and every check runs."""
from __future__ import annotations

import json
import os
from pathlib import Path

import pytest
import yaml

from firmware.checks import FAILED, OK, SKIPPED, run_checks
from firmware.render import render, write
from platform_tools.rig import load_rig

SNAPSHOTS = Path(__file__).parent / "snapshots"
SERIALS = ("--set", "sensors.thermal.left.serial=93588", "--set", "sensors.thermal.right.serial=93599")


def rendered(*overrides: str) -> dict[str, str]:
    return {o.path: o.text for o in render(load_rig(None, overrides))}


def params(files: dict[str, str], name: str) -> dict:
    return yaml.safe_load(files[f"config/{name}.yaml"])["/**"]["ros__parameters"]


@pytest.fixture(scope="module")
def default_render(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("fw") / "firmware"
    write(load_rig(None, [SERIALS[1], SERIALS[3]]), out)
    return out


@pytest.mark.slow
def test_every_check_passes_on_the_default_rig(default_render):
    results = run_checks(default_render, load_rig(None, [SERIALS[1], SERIALS[3]]))
    assert [r for r in results if r.status == FAILED] == []
    assert {r.name for r in results if r.status == OK} >= {"compose matches rig", "launch files", "udev rules",
                                                           "parameter files", "systemd unit"}


@pytest.mark.slow
@pytest.mark.parametrize("tool,check", [("docker-compose", "compose valid"), ("shellcheck", "shellcheck")])
def test_real_validators_run_when_installed(default_render, tool, check):
    import shutil
    result = {r.name: r for r in run_checks(default_render, load_rig())}[check]
    if shutil.which(tool) is None:
        assert result.status == SKIPPED  # reported as skipped, never as passed
        pytest.skip(f"{tool} is not installed (bootstrap.sh installs it)")
    assert result.status == OK, result.detail


def test_snapshot_of_the_default_rig():
    """The whole rendered configuration, against a reviewed copy. The rig hash is masked (it changes
    with any edit of rig.yaml, on-device or not). After a deliberate change, update the copy with
    UPDATE_SNAPSHOTS=1 and review the diff."""
    rig = load_rig(None, [SERIALS[1], SERIALS[3]])
    files = {o.path: o.text.replace(rig.hash, "<rig-hash>").replace(rig.hash[:12], "<rig-hash>")
             for o in render(rig) if o.path != "config/rig.yaml" and not o.vendored}   # not the copied source
    if os.environ.get("UPDATE_SNAPSHOTS"):
        for path, text in files.items():
            (SNAPSHOTS / path).parent.mkdir(parents=True, exist_ok=True)
            (SNAPSHOTS / path).write_text(text)
    for path, text in files.items():
        snap = SNAPSHOTS / path
        assert snap.is_file(), f"no snapshot {snap}: run with UPDATE_SNAPSHOTS=1 and review"
        assert text == snap.read_text(), f"{path} differs from {snap}: review, then UPDATE_SNAPSHOTS=1"
    assert sorted(str(p.relative_to(SNAPSHOTS)) for p in SNAPSHOTS.rglob("*")
                  if p.is_file() and "__pycache__" not in p.parts) == sorted(files)


def test_trigger_rate_reaches_the_thermal_drivers():
    files = rendered("sync.rate_hz=60")
    assert params(files, "thermal_left")["framerate"] == 60.0
    assert params(files, "thermal_right")["framerate"] == 60.0


def test_stop_grace_reaches_compose_and_systemd():
    files = rendered("recording.stop_grace_s=40", "on_device.recorder_term_grace_s=7")
    compose = yaml.safe_load(files["compose.yaml"])
    assert compose["services"]["recorder"]["stop_grace_period"] == "57s"    # 40 + 7 + slack 10
    assert "TimeoutStopSec=67" in files["systemd/rgbt-rig.service"]
    assert "STOP_TIMEOUT_S=57" in files["bin/rig-down.sh"]


def test_data_mount_reaches_unit_compose_and_start_script():
    files = rendered("recording.data_mount=/mnt/nvme", "recording.output_dir=/mnt/nvme/rec")
    assert "RequiresMountsFor=/mnt/nvme\n" in files["systemd/rgbt-rig.service"]
    assert "/mnt/nvme:/mnt/nvme" in yaml.safe_load(files["compose.yaml"])["services"]["recorder"]["volumes"]
    assert "DATA_MOUNT=/mnt/nvme\n" in files["bin/rig-up.sh"]


def test_baseline_reaches_the_static_transforms(tmp_path):
    rig = load_rig(None, ["sensors.thermal.baseline_mm=150"])
    write(rig, tmp_path / "fw")
    from firmware.launch_stub import load_launch_file
    nodes = load_launch_file(tmp_path / "fw" / "launch" / "zed.launch.py").entities
    tf = {n.kwargs["name"]: n.kwargs["arguments"] for n in nodes if n.kwargs.get("name", "").startswith("tf_")}
    y = lambda args: float(args[args.index("--y") + 1])  # noqa: E731
    assert y(tf["tf_thermal_left"]) == pytest.approx(0.075)
    assert y(tf["tf_thermal_right"]) == pytest.approx(-0.075)


def test_topics_and_devices_follow_the_rig():
    files = rendered("on_device.topics.thermal_left=/ir/l/image", "sensors.thermal.left.device_name=flir_a")
    assert "/ir/l/image" in files["launch/thermal.launch.py"]
    assert params(files, "thermal_left")["video_device"] == "/dev/flir_a_video"
    devices = yaml.safe_load(files["compose.yaml"])["services"]["thermal_left"]["devices"]
    assert devices == ["/dev/flir_a_video:/dev/flir_a_video"]


def test_zed_resolution_follows_the_camera_model():
    assert params(rendered("camera_models.zed_x_hd1200.height_px=1080"), "zed")["general"]["grab_resolution"] == "HD1080"


@pytest.mark.slow
def test_udev_rules_name_cameras_only_when_serials_are_known():
    assert "SYMLINK" not in rendered()["udev/99-rgbt-boson.rules"]
    rules = rendered(SERIALS[1], SERIALS[3])["udev/99-rgbt-boson.rules"]
    assert 'ATTRS{serial}=="93588"' in rules and 'SYMLINK+="boson_left_video"' in rules
    assert 'ATTRS{serial}=="93599"' in rules and 'SYMLINK+="boson_right_serial"' in rules


def test_rendered_rig_file_is_the_rig_that_was_rendered(default_render):
    assert load_rig(default_render / "config" / "rig.yaml").hash == load_rig(None, [SERIALS[1], SERIALS[3]]).hash


# ----------------------------------------------------------------------------- the command
@pytest.mark.slow
def test_render_command_writes_a_checked_folder(platform_tools, tmp_path):
    r = platform_tools("firmware", "render", "--out", str(tmp_path / "fw"), "--json")
    assert r.returncode == 0, r.stderr
    doc = json.loads(r.stdout)
    assert not [c for c in doc["checks"] if c["status"] == FAILED]
    assert len(doc["warnings"]) == 2                      # serials not set in config/rig.yaml
    assert os.access(tmp_path / "fw" / "bin" / "rig-up.sh", os.X_OK)
    assert json.loads((tmp_path / "fw" / "MANIFEST.json").read_text())["rig_hash"] == doc["rig_hash"]


@pytest.mark.slow
def test_a_relative_output_folder(platform_tools, tmp_path):
    r = platform_tools("firmware", "render", "--out", "fw", "-q", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "fw" / "compose.yaml").is_file()


@pytest.mark.slow
def test_a_failed_check_leaves_the_previous_output(platform_tools, tmp_path):
    out = tmp_path / "fw"
    assert platform_tools("firmware", "render", "--out", str(out), "-q").returncode == 0
    before = (out / "MANIFEST.json").read_text()
    r = platform_tools("firmware", "render", "--out", str(out), "--set", "on_device.gpio_chips=[/dev/gpio:chip0]")
    assert r.returncode == 1
    assert "compose matches rig failed" in r.stderr and "left unchanged" in r.stderr
    assert (out / "MANIFEST.json").read_text() == before
    assert [p.name for p in tmp_path.iterdir()] == ["fw"]   # no staging folder left behind


@pytest.mark.slow
def test_a_bad_rig_value_is_one_line_and_exit_2(platform_tools, tmp_path):
    r = platform_tools("firmware", "render", "--out", str(tmp_path / "fw"),
                       "--set", "camera_models.zed_x_hd1200.height_px=700")
    assert r.returncode == 2
    assert "height_px: 700 is not a ZED X resolution" in r.stderr and "Traceback" not in r.stderr
    assert not (tmp_path / "fw").exists()


@pytest.mark.slow
@pytest.mark.parametrize("edit,check", [
    (("compose.yaml", "stop_grace_period: 30s", "stop_grace_period: 5s"), "compose matches rig"),
    (("bin/rig-up.sh", 'cd "$(dirname "$0")/.."', 'cd $(dirname $0)/..'), "shellcheck"),
    (("launch/thermal.launch.py", "def camera_node(context):", "def camera_node(context)"), "launch files"),
    (("systemd/rgbt-rig.service", "RestartSec=10", "RestartSec=10\nFrobnicate=yes"), "systemd unit"),
    (("udev/99-rgbt-boson.rules", 'SYMLINK+="boson_left_video"', 'SYMLINK+=boson_left_video'), "udev rules"),
    (("compose.yaml", "    init: true", "    init: true\n    bogus_key: 1"), "compose valid"),
    (("docker/tools/Dockerfile", "COPY src/rgbt-rig", "COPY src/not-there"), "dockerfiles"),
    (("docker/zed/Dockerfile", "l4t-jetpack:r36.4.0", "l4t-jetpack:r35.4.1"), "dockerfiles"),
    (("launch/thermal.launch.py", '"firmware.device.ffc_node"', '"platform_tools.boson.telemetry.nod"'),
     "launch files"),
])
def test_check_command_catches_a_tampered_file(platform_tools, tmp_path, edit, check):
    out = tmp_path / "fw"
    assert platform_tools("firmware", "render", "--out", str(out), "-q", *SERIALS).returncode == 0
    name, old, new = edit
    text = (out / name).read_text()
    assert old in text
    (out / name).write_text(text.replace(old, new, 1))
    r = platform_tools("firmware", "check", str(out), "--json", *SERIALS)
    results = {c["name"]: c["status"] for c in json.loads(r.stdout)["checks"]}
    if results[check] == SKIPPED:
        pytest.skip(f"the validator behind {check!r} is not installed")
    assert r.returncode == 1
    assert results[check] == FAILED
    assert [n for n, s in results.items() if s == FAILED] == [check]


# ----------------------------------------------------------------------------- images
def test_dockerfiles_follow_the_rig_and_compose_builds_them():
    files = rendered(*SERIALS[1::2])
    compose = yaml.safe_load(files["compose.yaml"])["services"]
    assert compose["zed"]["build"] == {"context": "./docker", "dockerfile": "zed/Dockerfile"}
    assert compose["thermal_right"]["build"]["dockerfile"] == "thermal/Dockerfile"
    assert compose["health"]["build"]["dockerfile"] == "tools/Dockerfile"
    assert "ARG BASE_IMAGE=nvcr.io/nvidia/l4t-jetpack:r36.4.0" in files["docker/zed/Dockerfile"]
    assert "ARG ROS_DISTRO=humble" in files["docker/zed/Dockerfile"]
    assert "ARG BASE_IMAGE=ros:humble-ros-base-jammy" in files["docker/thermal/Dockerfile"]
    assert "usb-cam" in files["docker/thermal/Dockerfile"] and "rosbag2-storage-mcap" in files["docker/tools/Dockerfile"]
    assert "Jetson.GPIO" in files["docker/tools/Dockerfile"]
    # this repository's source is in the build context the thermal and tools images COPY
    assert "docker/src/rgbt-rig/pyproject.toml" in files
    assert "docker/src/rgbt-rig/firmware/device/ffc_node.py" in files
    assert not any("__pycache__" in p for p in files)


def test_ros_distro_reaches_the_dockerfiles():
    files = rendered("on_device.ros_distro=iron", "on_device.images.zed=a/zed:iron-l4t-r36",
                     "on_device.images.thermal=a/th:iron-l4t-r36", "on_device.images.tools=a/tools:iron-l4t-r36")
    assert "ARG BASE_IMAGE=ros:iron-ros-base-jammy" in files["docker/tools/Dockerfile"]
    assert "ARG ROS_DISTRO=iron" in files["docker/zed/Dockerfile"]


@pytest.mark.slow
@pytest.mark.parametrize("override,message", [
    ("on_device.images.zed=a/zed:humble-l4t-r35", "different L4T releases"),
    ("on_device.images.tools=a/tools:latest", "names no L4T release"),
    ("on_device.ros_distro=jazzy", "no binary packages for L4T r36"),
])
def test_images_that_cannot_match_the_orin_are_one_line_and_exit_2(platform_tools, tmp_path, override, message):
    r = platform_tools("firmware", "render", "--out", str(tmp_path / "fw"), "--set", override)
    assert r.returncode == 2, r.stderr
    assert message in r.stderr and "Traceback" not in r.stderr
    assert not (tmp_path / "fw").exists()


def test_the_status_publisher_is_launched_for_each_side(default_render):
    from firmware.launch_stub import load_launch_file
    desc = load_launch_file(default_render / "launch" / "thermal.launch.py")
    fn = next(e for e in desc.entities if hasattr(e, "run"))
    for side in ("left", "right"):
        (proc,) = [e for e in fn.run({"side": side}) if e.kwargs.get("name") == f"thermal_{side}_status"]
        cmd = proc.kwargs["cmd"]
        assert cmd[:3] == ["python3", "-m", "firmware.device.ffc_node"]
        assert f"image_topic:=/thermal/{side}/image_raw" in cmd and f"status_topic:=/thermal/{side}/status" in cmd
        assert "telemetry_rows:=2" in cmd


@pytest.mark.slow
def test_the_images_install_only_firmware_and_what_it_imports(tmp_path):
    """The build context holds firmware, platform_tools.rig and platform_tools.boson, nothing else of
    this repository, and every on-device module imports from it alone (no platform_tools.cli, dataset,
    sim): run in a fresh process whose only copy of this repository is the rendered context."""
    import subprocess
    import sys
    rig = load_rig(None, [SERIALS[1], SERIALS[3]])
    write(rig, tmp_path / "fw")
    src = tmp_path / "fw" / "docker" / "src" / "rgbt-rig"
    packages = {p.parent.relative_to(src).as_posix() for p in src.rglob("__init__.py")}
    top = {p for p in packages if not any(p.startswith(q + "/") for q in packages)}
    assert top == {"firmware", "platform_tools"}
    assert {p for p in packages if p.count("/") == 1 and p.startswith("platform_tools/")} == \
        {"platform_tools/rig", "platform_tools/boson"}
    modules = sorted(".".join(p.relative_to(src).with_suffix("").parts) for p in (src / "firmware").rglob("*.py")
                     if p.name != "__init__.py" and p.stem not in ("ffc_node", "health_node"))   # need rclpy
    probe = ("import importlib, sys\n"
             f"for m in {modules!r}: importlib.import_module(m)\n"
             "ours = [m for m in sys.modules if m.split('.')[0] in ('firmware', 'platform_tools', 'calibration', "
             "'cad', 'bom')]\n"
             f"outside = [m for m in ours if not (sys.modules[m].__file__ or '').startswith({str(src)!r})]\n"
             "assert not outside, outside\n"
             "from firmware.cli import main\n"
             "raise SystemExit(main(['--help']))\n")
    r = subprocess.run([sys.executable, "-c", probe], cwd=tmp_path, env=dict(os.environ, PYTHONPATH=str(src)),
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    assert "record-service" in r.stdout and "doctor" in r.stdout


def test_the_device_command_is_what_compose_runs(default_render):
    compose = yaml.safe_load((default_render / "compose.yaml").read_text())["services"]
    assert compose["recorder"]["command"][1:3] == ["rig-device", "record-service"]
    assert compose["health"]["command"][1:3] == ["rig-device", "doctor"]
    assert 'rig-device = "firmware.cli:main"' in (Path(__file__).parents[2] / "pyproject.toml").read_text()


def test_the_images_install_only_the_device_console_script(tmp_path):
    """The images' pyproject.toml declares rig-device only: platform_tools and calibrate import modules
    the images do not have. A hand edit adding one fails `firmware check`."""
    import tomllib
    from firmware.checks import check_device_install
    rig = load_rig(None, [SERIALS[1], SERIALS[3]])
    out = tmp_path / "fw"
    write(rig, out)
    pyproject = out / "docker" / "src" / "rgbt-rig" / "pyproject.toml"
    doc = tomllib.loads(pyproject.read_text())
    repo = tomllib.loads((Path(__file__).parents[2] / "pyproject.toml").read_text())
    assert set(repo["project"]["scripts"]) >= {"platform_tools", "calibrate", "rig-device"}
    assert doc["project"]["scripts"] == {"rig-device": repo["project"]["scripts"]["rig-device"]}
    assert doc["project"]["version"] == repo["project"]["version"] and doc["project"]["dependencies"] == []
    assert check_device_install(out, rig).status == OK
    pyproject.write_text(pyproject.read_text().replace(
        "[project.scripts]\n", '[project.scripts]\nplatform_tools = "platform_tools.cli.main:main"\n'))
    c = check_device_install(out, rig)
    assert c.status == FAILED and "platform_tools.cli.main is not in the images' source" in c.detail
