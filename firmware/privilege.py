"""The least-privilege rules a rendered folder must keep: what each container may do, what its ROS 2
traffic reaches, how its image's downloads are verified, how the boot unit is hardened.

Pure reading of the rendered files (compose.yaml, the Dockerfiles, the systemd unit) against the rig:
each rule is one `Check` that `firmware check` runs, so a hand edit that widens a service fails it.
"""
from __future__ import annotations

import configparser
import re
from pathlib import Path

from platform_tools.rig.checks import FAILED, OK, Check
from platform_tools.rig import Rig
from platform_tools.rig.yamlsource import safe_load
from firmware.context import build_context

#: host paths no confined service may mount: the device tree, the kernel's views, the Docker socket
#: (root on the host), the host's root
FORBIDDEN_MOUNTS = ("/", "/dev", "/sys", "/proc", "/run/docker.sock", "/var/run/docker.sock", "/etc")
#: services that may run as root (without capabilities), and why
ROOT_SERVICES = {"recorder": "/dev/gpiochip* are root-only unless the host installs Jetson.GPIO's udev rules"}
#: ROS 2 services (they join the DDS domain); the health monitor has no ROS and no network
ROS_SERVICES_EXCLUDED = ("health",)
#: systemd directives the boot unit must set (a docker compose client needs none of what they take away)
UNIT_HARDENING = {"NoNewPrivileges": "yes", "ProtectSystem": "full", "ProtectHome": "read-only",
                  "PrivateTmp": "yes", "ProtectKernelTunables": "yes", "ProtectKernelModules": "yes",
                  "ProtectControlGroups": "yes", "RestrictSUIDSGID": "yes"}
#: a download in a Dockerfile RUN, and what counts as verifying it in the same RUN
_DOWNLOAD = re.compile(r"\b(curl|wget)\b[^&|;]*?(https?://\S+)")
_VERIFIED = re.compile(r"sha256sum\s+-c|gpg\s+--show-keys[^&]*fpr")


def _services(folder: Path) -> dict:
    return (safe_load((folder / "compose.yaml").read_text()) or {}).get("services") or {}


def _host_path(volume) -> str:
    src = volume.get("source", "") if isinstance(volume, dict) else str(volume).split(":")[0]
    return "/" + src.strip("/") if src.startswith("/") else src


def _uid(user) -> int | None:
    if user is None:
        return None
    head = str(user).split(":")[0]
    return int(head) if head.isdigit() else (0 if head == "root" else -1)


def check_least_privilege(folder: Path, rig: Rig) -> Check:
    """Only on_device.privileged_services may be privileged or share the host's pid namespace; every
    other service drops all capabilities, sets no-new-privileges, mounts none of FORBIDDEN_MOUNTS, gets
    exactly the devices the rig lists for it, and runs as a non-root user unless ROOT_SERVICES says why."""
    od = rig.desc.on_device
    want_devices = build_context(rig)["devices"]
    problems = []
    for name, svc in _services(folder).items():
        if name in od.privileged_services:
            continue
        if svc.get("privileged"):
            problems.append(f"{name} is privileged (only {', '.join(od.privileged_services)} may be)")
        if svc.get("pid") == "host":
            problems.append(f"{name} shares the host pid namespace")
        if "ALL" not in [str(c).upper() for c in svc.get("cap_drop") or []]:
            problems.append(f"{name} keeps its capabilities (no cap_drop: [ALL])")
        if svc.get("cap_add"):
            problems.append(f"{name} adds capabilities {svc['cap_add']}")
        if not any(str(o).replace("=", ":") in ("no-new-privileges:true", "no-new-privileges")
                   for o in svc.get("security_opt") or []):
            problems.append(f"{name} may gain privileges (no security_opt no-new-privileges:true)")
        for v in svc.get("volumes") or []:
            if _host_path(v) in FORBIDDEN_MOUNTS:
                problems.append(f"{name} mounts {_host_path(v)}")
        devices = sorted(str(d) for d in svc.get("devices") or [])
        if devices != sorted(want_devices.get(name, [])):
            problems.append(f"{name} devices {devices}, the rig gives it {sorted(want_devices.get(name, []))}")
        uid = _uid(svc.get("user"))
        if name not in ROOT_SERVICES and (uid is None or uid == 0):
            problems.append(f"{name} runs as root (user: {svc.get('user', 'not set')})")
    if problems:
        return Check("least privilege", FAILED, "; ".join(problems))
    return Check("least privilege", OK, f"privileged: {', '.join(od.privileged_services) or 'none'}; every other "
                                        f"service without capabilities, with only its own devices")


def check_dds(folder: Path, rig: Rig) -> Check:
    """Every ROS service is in the rig's non-zero domain, with the rig's discovery range and SROS2."""
    want = build_context(rig)["ros_env"]
    problems = []
    if rig.desc.on_device.ros_domain_id == 0:
        problems.append("on_device.ros_domain_id is 0, the domain every ROS 2 machine joins by default")
    for name, svc in _services(folder).items():
        if name in ROS_SERVICES_EXCLUDED:
            if svc.get("network_mode") != "none":
                problems.append(f"{name} needs no network (network_mode: {svc.get('network_mode')})")
            continue
        env = {k: str(v) for k, v in (svc.get("environment") or {}).items()}
        for key, value in want.items():
            if env.get(key) != value:
                problems.append(f"{name} {key}={env.get(key, 'unset')}, the rig says {value}")
        if env.get("ROS_DOMAIN_ID") == "0" and "ROS_DOMAIN_ID" not in want:
            problems.append(f"{name} ROS_DOMAIN_ID=0")
    if problems:
        return Check("dds exposure", FAILED, "; ".join(problems))
    return Check("dds exposure", OK, f"domain {want['ROS_DOMAIN_ID']}, discovery {rig.desc.on_device.dds_discovery}"
                                     + (", SROS2 enforced" if "ROS_SECURITY_ENABLE" in want else ""))


def unverified_downloads(dockerfile_text: str) -> list[str]:
    """URLs a Dockerfile downloads (curl, wget) in a RUN that does not verify them (sha256sum -c, or
    a gpg key fingerprint compared)."""
    text = re.sub(r"\\\n", " ", dockerfile_text)
    out = []
    for line in text.splitlines():
        if not line.lstrip().upper().startswith("RUN"):
            continue
        for _, url in _DOWNLOAD.findall(line):
            if not _VERIFIED.search(line):
                out.append(url.strip('"'))
    return out


def check_downloads(folder: Path, rig: Rig) -> Check:
    """Every download in every rendered Dockerfile is verified in its own RUN, and the base images carry
    the rig's digests when it holds them."""
    images = build_context(rig)["images"]
    problems, n = [], 0
    for name, rel in images["dockerfiles"].items():
        path = folder / rel
        if not path.is_file():
            continue   # the dockerfiles check reports it
        text = path.read_text()
        n += len(_DOWNLOAD.findall(re.sub(r"\\\n", " ", text)))
        problems += [f"{rel}: {url} is not verified (sha256sum -c or a key fingerprint)"
                     for url in unverified_downloads(text)]
        base = images["pinned"]["base" if name == "zed" else "ros_base"]
        if "@sha256:" in base and f"ARG BASE_IMAGE={base}" not in text:
            problems.append(f"{rel}: base image is not {base} (on_device.base_images)")
    if images["zed_sdk_sha256"] and not re.fullmatch(r"[0-9a-f]{64}", images["zed_sdk_sha256"]):
        problems.append(f"on_device.downloads.zed_sdk_sha256: {images['zed_sdk_sha256']!r} is not a sha256")
    if problems:
        return Check("verified downloads", FAILED, "; ".join(problems))
    return Check("verified downloads", OK, f"{n} downloads, each verified in its RUN")


def check_unit_hardening(folder: Path) -> Check:
    path = folder / "systemd" / "rgbt-rig.service"
    parser = configparser.ConfigParser(strict=False, interpolation=None)
    parser.optionxform = str
    try:
        parser.read_string(path.read_text())
    except configparser.Error as exc:
        return Check("unit hardening", FAILED, f"{path.name}: {exc}")
    unit = parser["Unit"] if parser.has_section("Unit") else {}
    service = parser["Service"] if parser.has_section("Service") else {}
    problems = [f"{k}={service.get(k, 'unset')}, expected {v}" for k, v in UNIT_HARDENING.items()
                if service.get(k) != v]
    if "network-online.target" in unit.get("After", "") and "network-online.target" not in unit.get("Wants", ""):
        problems.append("After=network-online.target without Wants=network-online.target (it is never pulled in)")
    if problems:
        return Check("unit hardening", FAILED, "; ".join(problems))
    return Check("unit hardening", OK, f"{len(UNIT_HARDENING)} hardening directives; network-online.target wanted")


def run(folder: Path, rig: Rig) -> list[Check]:
    return [check_least_privilege(folder, rig), check_dds(folder, rig), check_downloads(folder, rig),
            check_unit_hardening(folder)]
