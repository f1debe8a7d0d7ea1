"""The loaded rig: the validated description plus the values every view derives from it.

Derived values live here, once: the pose of every sensor frame in the rig frame, the nominal focal
length in pixels, the width of a thermal camera with its heat sink. The CAD model, the extrinsics,
the synthetic cameras and the on-device configuration all read them from here.
"""
from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator

from platform_tools.rig.frames import T_BODY_OPTICAL, Pose
from .schema import CameraModelSpec, Confidence, Part, RigDescription, Sourced
from .typed import KeyPath, format_path, to_data


@dataclass(frozen=True)
class SensorFrame:
    """A named frame of a sensor, posed in the rig frame."""
    name: str
    parent: str            # the frame it is attached to, for a URDF-like tree
    T_rig: Pose            # pose of this frame in the rig frame
    optical: bool          # an optical frame (x right, y down, z forward)
    camera_model: str | None = None


@dataclass(frozen=True)
class Estimate:
    path: str
    value: float
    source: str
    note: str | None


@dataclass(frozen=True)
class Rig:
    """A validated rig description and where it came from."""
    desc: RigDescription
    path: Path
    overrides: tuple[str, ...] = ()

    # ------------------------------------------------------------------ identity
    def to_data(self) -> dict:
        return to_data(self.desc)

    @property
    def hash(self) -> str:
        """sha256 of the resolved description (overrides included), stable across key order."""
        text = json.dumps(self.to_data(), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()

    # ------------------------------------------------------------------ parts
    def part(self, part_id: str) -> Part:
        return self.desc.parts[part_id]

    def dim(self, part_id: str, name: str) -> float:
        """A part-specific dimension's value (KeyError names the part and the dimension)."""
        try:
            return self.desc.parts[part_id].dims[name].value
        except KeyError:
            raise KeyError(f"parts.{part_id}.dims.{name} is not in the rig description") from None

    def thermal_module_width_mm(self) -> float:
        """Width (across the baseline) of one Boson with its heat sink: body + wall and fins on both sides."""
        body = self.part(self.desc.sensors.thermal.part).envelope_mm.y.value
        hs = self.desc.enclosure.heat_sink
        return body + 2 * (hs.wall_mm + hs.fin_height_mm)

    # ------------------------------------------------------------------ cameras
    def boson_device_nodes(self, side: str) -> dict[str, str]:
        """The names, relative to /dev, that the udev rules give the ``side`` ("left" or "right")
        Boson: ``{"video": "<device_name>_video", "serial": "<device_name>_serial"}`` (its V4L2 video
        node and its serial control port; device_name is sensors.thermal.<side>.device_name)."""
        name = getattr(self.desc.sensors.thermal, side).device_name
        return {"video": f"{name}_video", "serial": f"{name}_serial"}

    def camera_model(self, name: str) -> CameraModelSpec:
        return self.desc.camera_models[name]

    @staticmethod
    def focal_px(model: CameraModelSpec) -> float:
        """Nominal focal length in pixels: focal length / pixel pitch."""
        return model.focal_length_mm.value * 1000.0 / model.pixel_pitch_um.value

    @staticmethod
    def hfov_from_focal_deg(model: CameraModelSpec) -> float:
        """The horizontal field of view the nominal focal length implies, for the model's projection
        (pinhole: r = f tan(theta); fisheye, taken as equidistant: r = f theta)."""
        half_w = model.width_px / 2.0
        f = Rig.focal_px(model)
        half = math.atan(half_w / f) if model.projection == "pinhole" else half_w / f
        return math.degrees(2 * half)

    # ------------------------------------------------------------------ frames
    def sensor_frames(self) -> dict[str, SensorFrame]:
        """Every sensor frame in the rig frame: the ZED X centre, its left/right optical frames and
        IMU, and the two thermal cameras with their optical frames. A new dict each call, of the frames
        computed once per rig (both are immutable: the firmware's render asked for them 108 times, 0.85 s)."""
        return dict(self._sensor_frames)

    @functools.cached_property
    def _sensor_frames(self) -> dict[str, SensorFrame]:
        s = self.desc.sensors
        frames: dict[str, SensorFrame] = {}

        zed = Pose.from_xyz_rpy_deg(s.zed_x.pose.xyz_mm, s.zed_x.pose.rpy_deg)
        frames["zed_x"] = SensorFrame("zed_x", "rig", zed, False)
        half_b = self.dim(s.zed_x.part, "baseline_mm") / 2.0
        for side, sign in (("left", 1.0), ("right", -1.0)):
            body = zed @ Pose.from_xyz_rpy_deg((0.0, sign * half_b, 0.0))
            frames[f"zed_x_{side}"] = SensorFrame(f"zed_x_{side}", "zed_x", body, False)
            frames[f"zed_x_{side}_optical"] = SensorFrame(
                f"zed_x_{side}_optical", f"zed_x_{side}", body @ T_BODY_OPTICAL, True, s.zed_x.camera_model)
        imu = [self.dim(s.zed_x.part, f"imu_{a}_mm") for a in "xyz"]
        frames["zed_x_imu"] = SensorFrame("zed_x_imu", "zed_x", zed @ Pose.from_xyz_rpy_deg(imu), False)

        pair = Pose.from_xyz_rpy_deg(s.thermal.pose.xyz_mm, s.thermal.pose.rpy_deg)
        half_t = s.thermal.baseline_mm / 2.0
        for side, sign in (("left", 1.0), ("right", -1.0)):
            body = pair @ Pose.from_xyz_rpy_deg((0.0, sign * half_t, 0.0))
            frames[f"thermal_{side}"] = SensorFrame(f"thermal_{side}", "rig", body, False)
            frames[f"thermal_{side}_optical"] = SensorFrame(
                f"thermal_{side}_optical", f"thermal_{side}", body @ T_BODY_OPTICAL, True, s.thermal.camera_model)
        return frames

    def frame(self, name: str) -> Pose:
        frames = self.sensor_frames()
        if name not in frames:
            raise KeyError(f"no sensor frame {name!r}; the rig has {', '.join(frames)}")
        return frames[name].T_rig

    def T(self, a: str, b: str) -> Pose:
        """Pose of frame b in frame a (``T_a_b``); 'rig' names the rig frame."""
        Ta = Pose.identity() if a == "rig" else self.frame(a)
        Tb = Pose.identity() if b == "rig" else self.frame(b)
        return Ta.inverse() @ Tb

    # ------------------------------------------------------------------ provenance
    def estimates(self) -> list[Estimate]:
        """Every vendor number whose confidence is only an estimate, with its key path."""
        return [Estimate(format_path(p), s.value, s.source, s.note)
                for p, s in _walk_sourced(self.desc, ()) if s.confidence is Confidence.ESTIMATE] + [
            Estimate(format_path(("parts", pid, "mounting", i)), float(len(m.positions_mm)), m.source,
                     f"{m.thread} holes on the {m.face.value} face")
            for pid, part in self.desc.parts.items() for i, m in enumerate(part.mounting)
            if m.confidence is Confidence.ESTIMATE]


def _walk_sourced(value, path: KeyPath) -> Iterator[tuple[KeyPath, Sourced]]:
    if isinstance(value, Sourced):
        yield path, value
    elif dataclasses.is_dataclass(value):
        for f in dataclasses.fields(value):
            yield from _walk_sourced(getattr(value, f.name), path + (f.name,))
    elif hasattr(value, "items"):
        for k, v in value.items():
            yield from _walk_sourced(v, path + (k,))
    elif isinstance(value, tuple):
        for i, v in enumerate(value):
            yield from _walk_sourced(v, path + (i,))


def frames_table(rig: Rig) -> list[dict]:
    """Rows for printing or writing the sensor frames (mm and degrees, quaternion x y z w)."""
    rows = []

    def clean(v: float) -> float:  # no -0.0 in tables; 1e-12 mm is rounding noise
        return 0.0 if abs(v) < 1e-12 else float(v)

    for f in rig.sensor_frames().values():
        x, y, z = f.T_rig.t
        roll, pitch, yaw = f.T_rig.rpy_deg()
        qx, qy, qz, qw = f.T_rig.quaternion()
        values = dict(x_mm=x, y_mm=y, z_mm=z, roll_deg=roll, pitch_deg=pitch, yaw_deg=yaw, qx=qx, qy=qy, qz=qz, qw=qw)
        rows.append(dict(frame=f.name, parent=f.parent, optical=f.optical,
                         **{k: clean(v) for k, v in values.items()}))
    return rows


__all__ = ["Rig", "SensorFrame", "Estimate", "frames_table"]
