"""What the firmware templates see: every value they render, derived from the rig description once.

Templates never compute: units are converted, device paths, grace periods and frame transforms are
worked out here, so a reader of a template sees only names.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, fields

from platform_tools.boson.discovery import USB_PID, USB_VID
from platform_tools.rig import Rig
from firmware import camerainfo, v4l2
from firmware.device import health
from firmware.device.topics import health_cameras

#: frames the ZED wrapper does not publish: the thermal cameras, posed from the ZED X centre
THERMAL_FRAMES = ("thermal_left", "thermal_left_optical", "thermal_right", "thermal_right_optical")
#: slack on top of the recorder's own stop escalation: MCAP check/recovery and the metadata file
STOP_SLACK_S = 10.0


#: L4T releases the container images can be built for (the image tags in on_device.images name one:
#: "...-l4t-r36"): NVIDIA's JetPack container for it (CUDA, cuDNN, TensorRT: the ZED SDK's NEURAL
#: depth needs them), its L4T version (the ZED SDK is built per L4T minor) and its Ubuntu release
#: (which ROS 2 distributions have binary packages for it). JetPack 6.1 = L4T 36.4 on Ubuntu 22.04.
L4T_RELEASES = {
    "r36": {"base": "nvcr.io/nvidia/l4t-jetpack:r36.4.0", "l4t": "36.4", "l4t_revision": "4.4", "jetpack": "6.1",
            "ubuntu": "jammy"},
}
#: ROS 2 distributions with arm64 binary packages on packages.ros.org, per Ubuntu release
ROS_FOR_UBUNTU = {"jammy": ("humble", "iron"), "noble": ("jazzy",)}
#: the ZED SDK major.minor for the L4T above, and the zed-ros2-wrapper release built against it
#: (download.stereolabs.com/zedsdk/<sdk>/l4t<l4t>/jetsons; the wrapper tag must match the SDK: verify
#: both exist before the first build on the Orin)
#: The released TartanRGBT workspace runs L4T R36.4.4 with ZED SDK 5.0.0 (upstream-tartanrgbt.md): the
#: pairing known to work on this rig. The wrapper tag for SDK 5.0 is an assumption (doctor --bring-up).
ZED_SDK = "5.0"
ZED_ROS2_WRAPPER_REF = "humble-v5.0.0"
#: the ZED SDK installer for an SDK major.minor and an L4T major.minor (what zed_sdk_sha256 pins)
ZED_SDK_URL = "https://download.stereolabs.com/zedsdk/{sdk}/l4t{l4t}/jetsons"
#: the ROS 2 apt key (its fingerprint, not its file, is verified: on_device.downloads)
ROS_APT_KEY_URL = "https://raw.githubusercontent.com/ros/rosdistro/master/ros.key"
#: environment variable that limits DDS discovery to the host, per ROS distribution (humble has only
#: ROS_LOCALHOST_ONLY; iron added ROS_AUTOMATIC_DISCOVERY_RANGE, jazzy deprecates the former)
DISCOVERY_ENV = {
    "humble": {"localhost": {"ROS_LOCALHOST_ONLY": "1"}, "subnet": {"ROS_LOCALHOST_ONLY": "0"}},
    "iron": {"localhost": {"ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"},
             "subnet": {"ROS_AUTOMATIC_DISCOVERY_RANGE": "SUBNET"}},
    "jazzy": {"localhost": {"ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"},
              "subnet": {"ROS_AUTOMATIC_DISCOVERY_RANGE": "SUBNET"}},
}
#: where SROS2 keys live on the host (`rig-device sros2-keys` writes them) and inside the containers
KEYSTORE_DIR = "keystore"
KEYSTORE_MOUNT = "/keystore"
#: the SROS2 enclave names are /<ENCLAVE_ROOT>/<compose service>
ENCLAVE_ROOT = "rgbt"
#: the compose service publishing /health/<camera>/frequency and /status (firmware.device.health_node)
HEALTH_SERVICE = "health_topics"
#: how often it publishes
HEALTH_PERIOD_S = 1.0
#: where the rendered folder keeps what the image builds need (compose.yaml's build contexts)
DOCKER_DIR = "docker"
#: this repository's installable source inside that folder (the thermal and tools images install it)
SOURCE_DIR = "src/rgbt-rig"


@dataclass(frozen=True)
class StaticTf:
    parent: str
    child: str
    xyz_m: tuple[float, float, float]
    quat_xyzw: tuple[float, float, float, float]


def zed_resolution(rig: Rig) -> str:
    """zed-ros2-wrapper grab_resolution from the ZED camera model's height (HD1200, HD1080, SVGA)."""
    model = rig.camera_model(rig.desc.sensors.zed_x.camera_model)
    names = {1200: "HD1200", 1080: "HD1080", 600: "SVGA"}
    if model.height_px not in names:
        raise ValueError(f"camera_models.{rig.desc.sensors.zed_x.camera_model}.height_px: {model.height_px} is not "
                         f"a ZED X resolution; expected one of {', '.join(map(str, names))}")
    return names[model.height_px]


def device_paths(rig: Rig, side: str) -> dict[str, str]:
    """The paths of one Boson's udev names: its video node and its serial (control) port."""
    return {kind: f"/dev/{name}" for kind, name in rig.boson_device_nodes(side).items()}


def static_tfs(rig: Rig) -> list[StaticTf]:
    """The thermal frames relative to the ZED wrapper's camera centre (= the rig's zed_x frame)."""
    parent = f"{rig.desc.on_device.zed_camera_name}_camera_center"
    frames = rig.sensor_frames()
    out = []
    for name in THERMAL_FRAMES:
        f = frames[name]
        T = rig.T("zed_x" if f.parent == "rig" else f.parent, name)
        par = parent if f.parent == "rig" else f.parent
        xyz = tuple(round(float(v) / 1000.0, 9) + 0.0 for v in T.t)
        q = tuple(round(float(v), 9) + 0.0 for v in T.quaternion())
        out.append(StaticTf(par, name, xyz, q))
    return out


def stop_budget_s(rig: Rig) -> dict[str, float]:
    """Seconds each layer waits for the one inside it to stop: recorder < container < systemd."""
    rec = rig.desc.recording.stop_grace_s + rig.desc.on_device.recorder_term_grace_s
    container = rec + STOP_SLACK_S
    return {"recorder_s": rec, "container_s": container, "systemd_s": container + STOP_SLACK_S}


def thermal_context(rig: Rig, side: str) -> dict:
    t = rig.desc.sensors.thermal
    model = rig.camera_model(t.camera_model)
    od = rig.desc.on_device
    cam = getattr(t, side)
    return {
        "side": side,
        "name": f"thermal_{side}",
        "serial": cam.serial,
        "device_name": cam.device_name,
        "devices": device_paths(rig, side),
        "udev_names": rig.boson_device_nodes(side),     # the same, relative to /dev (udev's SYMLINK)
        "width_px": model.width_px,
        "height_px": model.height_px + od.thermal_telemetry_rows,
        "image_height_px": model.height_px,
        "fps": float(rig.desc.sync.rate_hz),
        "frame_id": f"thermal_{side}_optical",
        "topic": getattr(od.topics, f"thermal_{side}"),
        "status_topic": getattr(od.topics, f"thermal_{side}_status"),
        "telemetry_rows": od.thermal_telemetry_rows,
        # usb_cam's control parameters, each explicit: nothing written unless the rig asks (firmware/v4l2.py)
        "controls": v4l2.rendered_params(rig),
        "camera_info_url": camerainfo.url(side),
        "camera_info_file": camerainfo.file_name(side),
    }


def images_context(rig: Rig) -> dict:
    """The three images: tags, the L4T release their tags name, the base image and ROS distribution."""
    od = rig.desc.on_device
    tags = {name: getattr(od.images, name) for name in ("zed", "thermal", "tools")}
    releases = {}
    for name, tag in tags.items():
        m = re.search(r"l4t-(r\d+)", tag)
        if m is None:
            raise ValueError(f"on_device.images.{name}: {tag!r} names no L4T release (expected a tag with "
                             f"l4t-rNN, e.g. l4t-r36): the image's base must match the Orin's JetPack")
        releases[name] = m.group(1)
    if len(set(releases.values())) != 1:
        raise ValueError(f"on_device.images: the tags name different L4T releases "
                         f"({', '.join(f'{k} {v}' for k, v in releases.items())}): one Orin runs one JetPack")
    release = next(iter(releases.values()))
    if release not in L4T_RELEASES:
        raise ValueError(f"on_device.images: L4T {release} has no known base image; known: {', '.join(L4T_RELEASES)}")
    l4t = L4T_RELEASES[release]
    if od.ros_distro not in ROS_FOR_UBUNTU[l4t["ubuntu"]]:
        raise ValueError(f"on_device.ros_distro: {od.ros_distro} has no binary packages for L4T {release} "
                         f"(Ubuntu {l4t['ubuntu']}); use one of {', '.join(ROS_FOR_UBUNTU[l4t['ubuntu']])}")
    for name, tag in tags.items():
        named = [d for u in ROS_FOR_UBUNTU.values() for d in u if re.search(rf"\b{d}\b", tag)]
        if named and od.ros_distro not in named:
            raise ValueError(f"on_device.images.{name}: {tag!r} names ROS {named[0]}, on_device.ros_distro is "
                             f"{od.ros_distro}")
    digests = od.base_images
    pinned = {"base": _pinned(l4t["base"], digests.l4t_jetpack_digest),
              "ros_base": _pinned(f"ros:{od.ros_distro}-ros-base-{l4t['ubuntu']}", digests.ros_digest)}
    return {"tags": tags, "release": release, **l4t, "ros_distro": od.ros_distro, "pinned": pinned,
            "zed_sdk_sha256": od.downloads.zed_sdk_sha256 or "",
            "ros_key_url": ROS_APT_KEY_URL, "ros_key_fingerprint": od.downloads.ros_apt_key_fingerprint,
            # the official ROS image (multi-arch: arm64) on the Ubuntu of this L4T, for the images without CUDA
            "ros_base": f"ros:{od.ros_distro}-ros-base-{l4t['ubuntu']}",
            "zed_sdk": ZED_SDK, "zed_wrapper_ref": ZED_ROS2_WRAPPER_REF,
            "zed_sdk_url": ZED_SDK_URL.format(sdk=ZED_SDK, l4t=l4t["l4t"]),
            "dir": DOCKER_DIR, "source_dir": SOURCE_DIR,
            "dockerfiles": {name: f"{DOCKER_DIR}/{name}/Dockerfile" for name in tags}}


def _pinned(ref: str, digest: str | None) -> str:
    """An image reference pinned by digest when the rig holds one (repo:tag@sha256:...)."""
    return f"{ref}@{digest}" if digest else ref


def service_devices(rig: Rig) -> dict[str, list[str]]:
    """Every device node each compose service gets ("host:container[:perms]"), and nothing more: the
    Boson video node to its driver, the GPIO chips and the Bosons' serial ports to the recorder (record
    button, pre-flight), the video nodes read-only to the health monitor (it checks they exist). The
    ZED service has none listed: it is privileged (docs/on-device.md says why)."""
    od = rig.desc.on_device
    video = {side: device_paths(rig, side)["video"] for side in ("left", "right")}
    serial = [device_paths(rig, side)["serial"] for side in ("left", "right")]
    out = {f"thermal_{side}": [f"{v}:{v}"] for side, v in video.items()}
    out["recorder"] = [f"{d}:{d}" for d in (*od.gpio_chips, *serial)]
    out["health"] = [f"{v}:{v}:r" for v in video.values()]
    return out


def enclaves(rig: Rig) -> dict[str, str]:
    """The SROS2 enclave of each compose service that runs ROS 2 nodes (ROS_SECURITY_ENCLAVE_OVERRIDE:
    every node of the container in it), as compose.yaml spells it and `rig-device sros2-keys` creates it."""
    services = ["zed", *(f"thermal_{side}" for side in ("left", "right")), "recorder", HEALTH_SERVICE]
    return {s: f"/{ENCLAVE_ROOT}/{s}" for s in services}


def health_context(rig: Rig) -> dict:
    """What the health publisher watches and where it publishes (config/health.yaml)."""
    return {"service": HEALTH_SERVICE, "expected_hz": float(rig.desc.sync.rate_hz), "period_s": HEALTH_PERIOD_S,
            "cameras": [{"name": cam, "camera_info_topic": info, **{f"{k}_topic": v for k, v in health.topics(cam).items()}}
                        for cam, info in health_cameras(rig).items()]}


def ros_env(rig: Rig) -> dict[str, str]:
    """The ROS 2 environment every ROS container shares: domain, discovery range, SROS2."""
    od = rig.desc.on_device
    env = {"ROS_DOMAIN_ID": str(od.ros_domain_id), **DISCOVERY_ENV[od.ros_distro][od.dds_discovery]}
    if od.sros2_enclaves:
        env |= {"ROS_SECURITY_KEYSTORE": KEYSTORE_MOUNT, "ROS_SECURITY_ENABLE": "true",
                "ROS_SECURITY_STRATEGY": "Enforce"}
    return env


def build_context(rig: Rig) -> dict:
    d = rig.desc
    od = d.on_device
    zed_model = rig.camera_model(d.sensors.zed_x.camera_model)
    vid, pid = f"{USB_VID:04x}", f"{USB_PID:04x}"  # the Boson's USB id, owned by the Boson tooling
    rec = d.recording
    return {
        "rig": d,
        "rig_hash": rig.hash,
        "od": od,
        "rec": rec,
        "button": rec.button,
        "sync": d.sync,
        "zed": {
            "camera_model": "zedx",
            "camera_name": od.zed_camera_name,
            "resolution": zed_resolution(rig),
            "fps": int(round(zed_model.fps)),
            "downscale": od.zed_pub_downscale_factor,
            "depth_mode": od.zed_depth_mode,
            "depth_openni": od.zed_depth_openni,
        },
        "thermal": [thermal_context(rig, "left"), thermal_context(rig, "right")],
        "v4l2_allow": sorted(v4l2.allowed_v4l2(rig)),
        "v4l2_guard": {"file": v4l2.GUARD_FILE, "mount": v4l2.GUARD_MOUNT},
        "boson_vid": vid,
        "boson_pid": pid,
        "topics": [getattr(od.topics, f.name) for f in fields(od.topics)],
        "static_tfs": static_tfs(rig),
        "stop": stop_budget_s(rig),
        "split_size_bytes": int(rec.split_size_gb * 1e9),
        "split_duration_s": int(math.ceil(rec.split_duration_s)),
        "cache_bytes": rec.cache_mb * 1024 * 1024,
        "config_dir": f"{od.install_dir}/config",
        "images": images_context(rig),
        "devices": service_devices(rig),
        "ros_env": ros_env(rig),
        "health": health_context(rig),
        "uid": od.container_uid,
        "keystore": {"dir": KEYSTORE_DIR, "mount": KEYSTORE_MOUNT, "enabled": od.sros2_enclaves,
                     "enclaves": enclaves(rig)},
    }
