"""The recording's bandwidth, computed from the rig: what each recorded topic writes per second, against
what the data drive sustains for rosbag2 (recording.write_budget_mb_per_s).

Rates are before compression (zstd only helps), from the image sizes and rates the rig holds; where a
size depends on the scene (JPEG) the figure is a named estimate that `doctor --bring-up` replaces with
a measurement of a real recording.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from platform_tools.rig.checks import FAILED, OK, Check
from platform_tools.rig import Rig
from firmware.device.topics import CRC_OFF_PRESETS, camera_info_topic, health_topics, recorded_topics, records_depth

MB = 1e6
#: bytes per pixel of a ZED JPEG (image_transport's compressed, quality 95 by default): an estimate for
#: natural scenes (about 4 bits per pixel), to be measured at bring-up
JPEG_BYTES_PER_PX = 0.5
#: zed-ros2-wrapper's IMU publishing rate (sensors.sensors_pub_rate) and a sensor_msgs/Imu in CDR
IMU_RATE_HZ = 200.0
IMU_MSG_BYTES = 330
#: small messages: a sensor_msgs/CameraInfo (plumb_bob), one DiagnosticArray (the FFC status, the
#: wrapper's diagnostics at 1 Hz), the static transforms once
CAMERA_INFO_BYTES = 400
#: a health message (std_msgs Float64 or String) in CDR with its MCAP record, once per second
HEALTH_MSG_BYTES_PER_S = 64.0
STATUS_MSG_BYTES = 400
DIAGNOSTICS_BYTES_PER_S = 4000.0
#: MCAP message records, chunk and index overhead on top of the payload
MCAP_OVERHEAD = 1.02


@dataclass(frozen=True)
class TopicRate:
    topic: str
    bytes_per_s: float
    basis: str        # how the figure is computed (and whether it is an estimate)

    def to_dict(self) -> dict:
        return {"topic": self.topic, "mb_per_s": round(self.bytes_per_s / MB, 3), "basis": self.basis}


def topic_rates(rig: Rig) -> list[TopicRate]:
    """What each topic of `recorded_topics(rig)` writes per second."""
    d = rig.desc
    od = d.on_device
    rate = float(d.sync.rate_hz)
    zed = rig.camera_model(d.sensors.zed_x.camera_model)
    zed_px = (zed.width_px / od.zed_pub_downscale_factor) * (zed.height_px / od.zed_pub_downscale_factor)
    thermal = rig.camera_model(d.sensors.thermal.camera_model)
    thermal_px = thermal.width_px * (thermal.height_px + od.thermal_telemetry_rows)
    t = od.topics
    rates = {
        t.zed_left: (zed_px * JPEG_BYTES_PER_PX * rate, f"{zed_px:.0f} px JPEG x {JPEG_BYTES_PER_PX} B/px (estimate)"),
        t.zed_right: (zed_px * JPEG_BYTES_PER_PX * rate, f"{zed_px:.0f} px JPEG x {JPEG_BYTES_PER_PX} B/px (estimate)"),
        t.thermal_left: (thermal_px * 2 * rate, f"{thermal_px} px mono16"),
        t.thermal_right: (thermal_px * 2 * rate, f"{thermal_px} px mono16"),
        t.zed_imu: (IMU_RATE_HZ * IMU_MSG_BYTES, f"{IMU_RATE_HZ:g} Hz sensor_msgs/Imu"),
        t.thermal_left_status: (STATUS_MSG_BYTES * rate, "one DiagnosticArray per frame"),
        t.thermal_right_status: (STATUS_MSG_BYTES * rate, "one DiagnosticArray per frame"),
        "/diagnostics": (DIAGNOSTICS_BYTES_PER_S, "the wrapper's diagnostics"),
        "/tf_static": (0.0, "latched, once"),
    }
    if records_depth(rig):
        bpp = 2 if od.zed_depth_openni else 4
        rates[t.zed_depth] = (zed_px * bpp * rate, f"{zed_px:.0f} px {'16UC1 mm' if bpp == 2 else '32FC1 m'}")
    for topic in health_topics(rig):
        rates[topic] = (HEALTH_MSG_BYTES_PER_S, "one health message per second")
    for image in (t.zed_left, t.zed_right, t.thermal_left, t.thermal_right):
        rates[camera_info_topic(image)] = (CAMERA_INFO_BYTES * rate, "one CameraInfo per frame")
    return [TopicRate(topic, rates[topic][0] * MCAP_OVERHEAD, rates[topic][1]) for topic in recorded_topics(rig)]


def total_mb_per_s(rig: Rig) -> float:
    return sum(r.bytes_per_s for r in topic_rates(rig)) / MB


def check_budget(folder: Path, rig: Rig) -> Check:
    """Fails when the recorded topics write more than recording.write_budget_mb_per_s."""
    rates = topic_rates(rig)
    total = sum(r.bytes_per_s for r in rates) / MB
    budget = rig.desc.recording.write_budget_mb_per_s
    top = sorted(rates, key=lambda r: -r.bytes_per_s)[:3]
    biggest = ", ".join(f"{r.topic} {r.bytes_per_s / MB:.1f}" for r in top)
    if total > budget:
        return Check("bandwidth budget", FAILED,
                     f"{len(rates)} topics write {total:.1f} MB/s > recording.write_budget_mb_per_s {budget:g} "
                     f"(largest: {biggest} MB/s); turn depth off (on_device.zed_depth_mode: NONE) or to 16-bit "
                     f"(zed_depth_openni), or raise zed_pub_downscale_factor")
    return Check("bandwidth budget", OK, f"{len(rates)} topics write {total:.1f} MB/s <= {budget:g} MB/s "
                                         f"(largest: {biggest} MB/s)")


def check_chunk_crcs(rig: Rig) -> Check:
    preset = rig.desc.recording.compression_preset
    if preset in CRC_OFF_PRESETS:
        return Check("chunk crcs", FAILED, f"recording.compression_preset {preset} writes no chunk CRCs: the check "
                                           f"after stopping could not verify the chunks; use zstd_small")
    return Check("chunk crcs", OK, f"storage preset {preset} writes chunk CRCs")
