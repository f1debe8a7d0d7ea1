"""What a recording holds: the rig's topics, each camera's camera_info, the static transforms and the
diagnostics, as the upstream stack names them; depth only when the rig computes it on the device.

Pure functions over the rig description: the recorder records `recorded_topics(rig)`, and the
bandwidth budget (`firmware/budget.py`) prices the same list.
"""
from __future__ import annotations

from firmware.device import health
from platform_tools.rig import Rig

#: the ROS 2 topics of the static transforms (the thermal frames: launch/thermal.launch.py) and of
#: the diagnostic aggregator input (zed-ros2-wrapper's diagnostic_updater publishes there)
TF_STATIC = "/tf_static"
DIAGNOSTICS = "/diagnostics"
#: MCAP storage presets that turn chunk CRCs off (upstream-tartanrgbt.md): the check after stopping
#: could not verify a chunk
CRC_OFF_PRESETS = ("zstd_fast",)


def camera_info_topic(image_topic: str) -> str:
    """The camera_info beside an image topic, as zed-ros2-wrapper and usb_cam publish it:
    /zed/zed_node/left/image_rect_color/compressed -> /zed/zed_node/left/camera_info,
    /thermal/left/image_raw -> /thermal/left/camera_info."""
    parts = image_topic.rstrip("/").split("/")
    if parts[-1] == "compressed":
        parts = parts[:-1]
    return "/".join(parts[:-1]) + "/camera_info"


def records_depth(rig: Rig) -> bool:
    return rig.desc.on_device.zed_depth_mode != "NONE"


def camera_image_topics(rig: Rig) -> dict[str, str]:
    t = rig.desc.on_device.topics
    return {"zed_left": t.zed_left, "zed_right": t.zed_right, "thermal_left": t.thermal_left,
            "thermal_right": t.thermal_right}


def health_cameras(rig: Rig) -> dict[str, str]:
    """Each camera the health publisher watches, by its upstream name (zed, thermal_left, thermal_right),
    with the camera_info topic it counts frames on (one per frame, beside the image)."""
    t = rig.desc.on_device.topics
    return {rig.desc.on_device.zed_camera_name: camera_info_topic(t.zed_left),
            "thermal_left": camera_info_topic(t.thermal_left), "thermal_right": camera_info_topic(t.thermal_right)}


def health_topics(rig: Rig) -> tuple[str, ...]:
    """/health/<camera>/frequency and /health/<camera>/status of every camera, as upstream names them."""
    return tuple(topic for cam in health_cameras(rig) for topic in health.topics(cam).values())


def recorded_topics(rig: Rig) -> tuple[str, ...]:
    """Every topic `ros2 bag record` is given, in a stable order, without duplicates."""
    t = rig.desc.on_device.topics
    names = [getattr(t, f) for f in t.__dataclass_fields__ if f != "zed_depth" or records_depth(rig)]
    names += [camera_info_topic(v) for v in camera_image_topics(rig).values()]
    names += [TF_STATIC, DIAGNOSTICS, *health_topics(rig)]
    return tuple(dict.fromkeys(names))
