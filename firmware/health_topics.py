"""The `firmware check` rule for the health topics: the rendered health publisher (config/health.yaml,
run by compose's health service) publishes /health/<camera>/frequency and /status for every camera,
spelled as the released TartanRGBT stack spells them, and each of those topics is recorded."""
from __future__ import annotations

from pathlib import Path

import yaml

from firmware.context import HEALTH_SERVICE
from firmware.device import health
from firmware.device.topics import health_cameras, recorded_topics
from platform_tools.rig import Rig
from platform_tools.rig.checks import FAILED, OK, Check
from platform_tools.rig.yamlsource import safe_load

NODE_MODULE = "firmware.device.health_node"
CONFIG = "config/health.yaml"


def check_health_topics(folder: Path, rig: Rig) -> Check:
    problems = []
    try:
        params = safe_load((folder / CONFIG).read_text())["/**"]["ros__parameters"]
    except (OSError, yaml.YAMLError, KeyError, TypeError) as exc:
        return Check("health topics", FAILED, f"{CONFIG}: {type(exc).__name__}: {exc}")
    recorded = set(recorded_topics(rig))
    for cam, info in health_cameras(rig).items():
        got = params.get(cam) if cam in (params.get("cameras") or []) else None
        if not isinstance(got, dict):
            problems.append(f"{cam}: not watched by the health publisher ({CONFIG})")
            continue
        if got.get("camera_info_topic") != info:
            problems.append(f"{cam}: counts frames on {got.get('camera_info_topic')}, the camera publishes {info}")
        for kind, want in health.topics(cam).items():
            topic = got.get(f"{kind}_topic")
            if topic != want:
                problems.append(f"{cam}: publishes {kind} on {topic}, upstream names it {want}")
            if topic not in recorded:
                problems.append(f"{topic} is not in the recorded topic list")
    svc = ((safe_load((folder / "compose.yaml").read_text()) or {}).get("services") or {}).get(HEALTH_SERVICE)
    command = [str(c) for c in (svc or {}).get("command") or []]
    if NODE_MODULE not in command or f"/{CONFIG}" not in command:
        problems.append(f"compose service {HEALTH_SERVICE} does not run {NODE_MODULE} with /{CONFIG}")
    if problems:
        return Check("health topics", FAILED, "; ".join(problems))
    n = 2 * len(health_cameras(rig))
    return Check("health topics", OK, f"{n} /health/<camera>/frequency|status topics published by "
                                      f"{HEALTH_SERVICE} and recorded")
