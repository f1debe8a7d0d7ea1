"""ROS 2 message definitions (as rosbag2 stores them in MCAP schemas: the message text, then each
dependency after a line of 80 '=' and ``MSG: pkg/Type``), and builders for their dict form.

Only the messages the rig records: sensor_msgs Image / CompressedImage / Imu and
diagnostic_msgs DiagnosticArray (the thermal status: FFC state and frame counter).
"""
from __future__ import annotations

import numpy as np

_SEP = "=" * 80

_DEFS = {
    "builtin_interfaces/Time": "int32 sec\nuint32 nanosec\n",
    "std_msgs/Header": "builtin_interfaces/Time stamp\nstring frame_id\n",
    "geometry_msgs/Quaternion": "float64 x\nfloat64 y\nfloat64 z\nfloat64 w\n",
    "geometry_msgs/Vector3": "float64 x\nfloat64 y\nfloat64 z\n",
    "diagnostic_msgs/KeyValue": "string key\nstring value\n",
    "diagnostic_msgs/DiagnosticStatus": (
        "byte OK=0\nbyte WARN=1\nbyte ERROR=2\nbyte STALE=3\n"
        "byte level\nstring name\nstring message\nstring hardware_id\ndiagnostic_msgs/KeyValue[] values\n"),
    "sensor_msgs/Image": ("std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\n"
                          "uint8 is_bigendian\nuint32 step\nuint8[] data\n"),
    "sensor_msgs/CompressedImage": "std_msgs/Header header\nstring format\nuint8[] data\n",
    "sensor_msgs/Imu": (
        "std_msgs/Header header\ngeometry_msgs/Quaternion orientation\nfloat64[9] orientation_covariance\n"
        "geometry_msgs/Vector3 angular_velocity\nfloat64[9] angular_velocity_covariance\n"
        "geometry_msgs/Vector3 linear_acceleration\nfloat64[9] linear_acceleration_covariance\n"),
    "diagnostic_msgs/DiagnosticArray": "std_msgs/Header header\ndiagnostic_msgs/DiagnosticStatus[] status\n",
}

_DEPS = {
    "std_msgs/Header": ["builtin_interfaces/Time"],
    "sensor_msgs/Image": ["std_msgs/Header"],
    "sensor_msgs/CompressedImage": ["std_msgs/Header"],
    "sensor_msgs/Imu": ["std_msgs/Header", "geometry_msgs/Quaternion", "geometry_msgs/Vector3"],
    "diagnostic_msgs/DiagnosticStatus": ["diagnostic_msgs/KeyValue"],
    "diagnostic_msgs/DiagnosticArray": ["std_msgs/Header", "diagnostic_msgs/DiagnosticStatus"],
}


def _closure(name: str) -> list[str]:
    out: list[str] = []
    for dep in _DEPS.get(name, []):
        for d in [dep] + _closure(dep):
            if d not in out:
                out.append(d)
    return out


def msgdef(name: str) -> tuple[str, str]:
    """(schema name as rosbag2 writes it, e.g. ``sensor_msgs/msg/Image``, full definition text)."""
    parts = [_DEFS[name]] + [f"{_SEP}\nMSG: {d}\n{_DEFS[d]}" for d in _closure(name)]
    pkg, typ = name.split("/")
    return f"{pkg}/msg/{typ}", "".join(parts)


def header(stamp_ns: int, frame_id: str) -> dict:
    return {"stamp": {"sec": int(stamp_ns // 1_000_000_000), "nanosec": int(stamp_ns % 1_000_000_000)},
            "frame_id": frame_id}


def image(stamp_ns: int, frame_id: str, pixels: np.ndarray, encoding: str) -> dict:
    """A sensor_msgs/Image from an array: mono16 (uint16), mono8 / bgr8 (uint8) or 32FC1 (float32)."""
    data = np.ascontiguousarray(pixels.astype(pixels.dtype.newbyteorder("<"), copy=False))
    h, w = data.shape[:2]
    return {"header": header(stamp_ns, frame_id), "height": h, "width": w, "encoding": encoding,
            "is_bigendian": 0, "step": int(data.strides[0]), "data": data.tobytes()}


def compressed_image(stamp_ns: int, frame_id: str, data: bytes, fmt: str = "jpeg") -> dict:
    return {"header": header(stamp_ns, frame_id), "format": fmt, "data": data}


def imu(stamp_ns: int, frame_id: str, gyro_rad_s, accel_m_s2, q_xyzw=(0.0, 0.0, 0.0, 1.0)) -> dict:
    x, y, z, w = q_xyzw
    cov = [0.0] * 9
    return {"header": header(stamp_ns, frame_id),
            "orientation": {"x": x, "y": y, "z": z, "w": w}, "orientation_covariance": cov,
            "angular_velocity": dict(zip("xyz", map(float, gyro_rad_s))), "angular_velocity_covariance": cov,
            "linear_acceleration": dict(zip("xyz", map(float, accel_m_s2))),
            "linear_acceleration_covariance": cov}


def diagnostic(stamp_ns: int, name: str, hardware_id: str, values: dict[str, object], level: int = 0,
               message: str = "") -> dict:
    return {"header": header(stamp_ns, ""),
            "status": [{"level": level, "name": name, "message": message,
                        "hardware_id": hardware_id,
                        "values": [{"key": k, "value": str(v)} for k, v in values.items()]}]}
