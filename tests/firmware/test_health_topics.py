"""Health topics named as the released TartanRGBT stack names them (its topic_list.yaml, quoted in
upstream-tartanrgbt.md), published by the health service, recorded; the rate and status decisions."""
from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from firmware import health_topics
from firmware.checks import FAILED, OK
from firmware.device import health
from firmware.device.topics import recorded_topics
from firmware.render import write
from platform_tools.rig import load_rig

#: upstream's names, copied from its topic list (not computed from this project's code)
UPSTREAM = {"/health/thermal_left/frequency", "/health/thermal_left/status", "/health/thermal_right/frequency",
            "/health/thermal_right/status", "/health/zed/frequency", "/health/zed/status"}
SERIALS = ("sensors.thermal.left.serial=93588", "sensors.thermal.right.serial=93599")


@pytest.fixture(scope="module")
def rig():
    return load_rig(None, list(SERIALS))


@pytest.fixture(scope="module")
def rendered(tmp_path_factory, rig) -> Path:
    out = tmp_path_factory.mktemp("health") / "fw"
    write(rig, out)
    return out


@pytest.fixture()
def folder(tmp_path, rendered) -> Path:
    """The rendered files the rule reads, copied (one render for the module)."""
    (tmp_path / "fw" / "config").mkdir(parents=True)
    for rel in ("compose.yaml", "config/health.yaml"):
        (tmp_path / "fw" / rel).write_text((rendered / rel).read_text())
    return tmp_path / "fw"


def test_the_upstream_health_topics_are_recorded(rig):
    assert UPSTREAM <= set(recorded_topics(rig))


@pytest.mark.slow
def test_the_default_render_passes(folder, rig):
    c = health_topics.check_health_topics(folder, rig)
    assert c.status == OK, c.detail
    svc = yaml.safe_load((folder / "compose.yaml").read_text())["services"]["health_topics"]
    assert svc["user"] == "1000:1000" and "devices" not in svc and svc["cap_drop"] == ["ALL"]


def _edit(folder: Path, fn) -> None:
    path = folder / "config" / "health.yaml"
    doc = yaml.safe_load(path.read_text())
    fn(doc["/**"]["ros__parameters"])
    path.write_text(yaml.safe_dump(doc))


@pytest.mark.slow
@pytest.mark.parametrize("edit,message", [
    (lambda p: p["thermal_left"].update(frequency_topic="/health/thermal_left/freq"),
     "publishes frequency on /health/thermal_left/freq, upstream names it /health/thermal_left/frequency"),
    (lambda p: p["cameras"].remove("zed"), "zed: not watched"),
    (lambda p: p["thermal_right"].update(camera_info_topic="/thermal/right/image_raw"), "counts frames on"),
])
def test_a_wrong_health_config_fails_firmware_check(folder, rig, edit, message):
    _edit(folder, edit)
    c = health_topics.check_health_topics(folder, rig)
    assert c.status == FAILED and message in c.detail, c.detail


@pytest.mark.slow
def test_an_unrecorded_health_topic_fails(folder, rig, monkeypatch):
    """The recorder's list without the health topics (as before issue 18): the rule names the first."""
    import firmware.health_topics as mod
    monkeypatch.setattr(mod, "recorded_topics", lambda r: tuple(t for t in recorded_topics(r)
                                                              if not t.startswith("/health/")))
    c = health_topics.check_health_topics(folder, rig)
    assert c.status == FAILED and "/health/zed/frequency is not in the recorded topic list" in c.detail


def test_frequency_and_status_from_frame_times():
    cam = health.CameraHealth("thermal_left", 30.0, window_s=2.0)
    assert cam.report(0.0) == (0.0, health.NO_DATA)
    for i in range(61):                      # 2 s at 30 Hz
        cam.on_frame(i / 30.0)
    hz, state = cam.report(2.0)
    assert hz == pytest.approx(30.0) and state == health.OK
    slow = health.CameraHealth("zed", 30.0)
    for i in range(31):                      # 15 Hz: every other trigger lost
        slow.on_frame(i / 15.0)
    assert slow.report(2.0) == (pytest.approx(15.0), health.LOW)
    assert cam.report(2.0 + health.STALE_S + 0.01)[1] == health.NO_DATA   # the stream stopped


def test_the_node_module_is_only_glue():
    """health_node.py needs rclpy (device only): it parses, and its decisions are health.CameraHealth's."""
    import ast
    src = (Path(health.__file__).parent / "health_node.py").read_text()
    tree = ast.parse(src)
    imported = {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
    assert {"rclpy.node", "sensor_msgs.msg", "std_msgs.msg", "firmware.device.health"} <= imported
    assert "CameraHealth" in src and "def main" in src
