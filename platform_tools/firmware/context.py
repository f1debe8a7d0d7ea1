"""What the firmware templates see: every value they render, derived from the rig description once.

Templates never compute: units are converted, device paths, grace periods and frame transforms are
worked out here, so a reader of a template sees only names.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, fields

from ..boson.discovery import USB_PID, USB_VID
from ..rig import Rig

#: frames the ZED wrapper does not publish: the thermal cameras, posed from the ZED X centre
THERMAL_FRAMES = ("thermal_left", "thermal_left_optical", "thermal_right", "thermal_right_optical")
#: slack on top of the recorder's own stop escalation: MCAP check/recovery and the metadata file
STOP_SLACK_S = 10.0


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
    """The udev names of one Boson: its video node and its serial (control) port."""
    name = getattr(rig.desc.sensors.thermal, side).device_name
    return {"video": f"/dev/{name}_video", "serial": f"/dev/{name}_serial"}


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
        "width_px": model.width_px,
        "height_px": model.height_px + od.thermal_telemetry_rows,
        "image_height_px": model.height_px,
        "fps": float(rig.desc.sync.rate_hz),
        "frame_id": f"thermal_{side}_optical",
        "topic": getattr(od.topics, f"thermal_{side}"),
        "status_topic": getattr(od.topics, f"thermal_{side}_status"),
    }


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
        },
        "thermal": [thermal_context(rig, "left"), thermal_context(rig, "right")],
        "boson_vid": vid,
        "boson_pid": pid,
        "topics": [getattr(od.topics, f.name) for f in fields(od.topics)],
        "static_tfs": static_tfs(rig),
        "stop": stop_budget_s(rig),
        "split_size_bytes": int(rec.split_size_gb * 1e9),
        "split_duration_s": int(math.ceil(rec.split_duration_s)),
        "cache_bytes": rec.cache_mb * 1024 * 1024,
        "config_dir": f"{od.install_dir}/config",
    }
