"""The camera_info each Boson's usb_cam publishes: a file rendered into config/, named by usb_cam's
``camera_info_url`` (camera_info_manager's ``file://`` form).

From the thermal calibration when the rig names one (``on_device.thermal_camera_info_<side>``: a ROS
camera_info YAML as `calibrate` writes it, calibration/formats/ros_camera_info.py; relative to the rig
file), copied with its source and sha256 in a header; else the **nominal** model: a pinhole with the rig's
nominal focal length (focal length / pixel pitch), the principal point at the image centre, no distortion.
The nominal model is only right near the centre of a 95 deg lens (the rig's nominal Boson model is
stereographic, which camera_info cannot express): a recording made with it says so (``nominal`` in the
file's first line) and must be re-projected with the calibration offline.

camera_info describes the image rows (``image_height`` 512 for a Boson 640), not the telemetry rows usb_cam
streams below them (514): whether camera_info_manager warns about the height difference is not verified here.
"""
from __future__ import annotations

import hashlib
from pathlib import Path

import yaml

from platform_tools.rig import Rig

#: where compose mounts the rendered config/ folder inside the thermal containers
CONTAINER_CONFIG_DIR = "/config"
#: the keys camera_calibration_parsers reads (spelled as it spells them)
KEYS = ("image_width", "image_height", "camera_name", "camera_matrix", "distortion_model",
        "distortion_coefficients", "rectification_matrix", "projection_matrix")


def file_name(side: str) -> str:
    return f"thermal_{side}_camera_info.yaml"


def url(side: str) -> str:
    return f"file://{CONTAINER_CONFIG_DIR}/{file_name(side)}"


def _matrix(rows: int, cols: int, data: list[float]) -> dict:
    return {"rows": rows, "cols": cols, "data": [float(x) for x in data]}


def nominal(rig: Rig, side: str) -> dict:
    model = rig.camera_model(rig.desc.sensors.thermal.camera_model)
    f = rig.focal_px(model)
    w, h = model.width_px, model.height_px
    cx, cy = (w - 1) / 2.0, (h - 1) / 2.0
    return {"image_width": w, "image_height": h, "camera_name": f"thermal_{side}",
            "camera_matrix": _matrix(3, 3, [f, 0, cx, 0, f, cy, 0, 0, 1]),
            "distortion_model": "plumb_bob", "distortion_coefficients": _matrix(1, 5, [0, 0, 0, 0, 0]),
            "rectification_matrix": _matrix(3, 3, [1, 0, 0, 0, 1, 0, 0, 0, 1]),
            "projection_matrix": _matrix(3, 4, [f, 0, cx, 0, 0, f, cy, 0, 0, 0, 1, 0])}


def source(rig: Rig, side: str) -> Path | None:
    name = getattr(rig.desc.on_device, f"thermal_camera_info_{side}")
    return None if name is None else (rig.path.parent / name)


def render(rig: Rig, side: str) -> tuple[str, str]:
    """(the file's text, "calibration <path>" or "nominal"); ValueError naming the rig key on a bad file."""
    key = f"on_device.thermal_camera_info_{side}"
    path = source(rig, side)
    model = rig.camera_model(rig.desc.sensors.thermal.camera_model)
    if path is None:
        doc, origin = nominal(rig, side), "nominal"
        head = (f"# nominal model of thermal_{side} (no {key} in the rig): pinhole, focal length / pixel pitch, "
                f"no distortion; re-project with the calibration offline")
    else:
        try:
            raw = path.read_bytes()
            doc = yaml.safe_load(raw)
        except (OSError, yaml.YAMLError) as exc:
            raise ValueError(f"{key}: {path}: {getattr(exc, 'strerror', None) or exc}") from None
        missing = [k for k in KEYS if not isinstance(doc, dict) or k not in doc]
        if missing:
            raise ValueError(f"{key}: {path}: not a ROS camera_info YAML (missing {', '.join(missing)})")
        if (doc["image_width"], doc["image_height"]) != (model.width_px, model.height_px):
            raise ValueError(f"{key}: {path}: {doc['image_width']}x{doc['image_height']}, the Boson model is "
                             f"{model.width_px}x{model.height_px}")
        doc = {k: doc[k] for k in KEYS} | {"camera_name": f"thermal_{side}"}
        origin = f"calibration {path}"
        head = f"# from the thermal calibration {path} (sha256 {hashlib.sha256(raw).hexdigest()})"
    return head + "\n" + yaml.safe_dump(doc, sort_keys=False, default_flow_style=None, width=200), origin
