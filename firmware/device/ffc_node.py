"""ROS 2 node: a Boson's FFC status from the telemetry rows of its images.

Runs in the thermal container, started by launch/thermal.launch.py next to usb_cam:

    python3 -m firmware.device.ffc_node --ros-args -r __node:=thermal_left_status \\
        -p image_topic:=/thermal/left/image_raw -p status_topic:=/thermal/left/status \\
        -p telemetry_rows:=2 -p hardware_id:=93588

Subscribes to the mono16 image, publishes diagnostic_msgs/DiagnosticArray on the status topic (the
one the recorder records). All decisions are in :mod:`firmware.device.ffc_status`; this module
only moves messages, and imports rclpy: it is imported on the device only.
"""
from __future__ import annotations

import sys

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rclpy.node import Node
from rclpy.qos import qos_profile_sensor_data
from sensor_msgs.msg import Image

from firmware.device.clockstep import ClockSteps
from firmware.device.ffc_status import StatusTracker
from firmware.device.rosnode import spin


def to_msg(d: dict) -> DiagnosticArray:
    msg = DiagnosticArray()
    msg.header.stamp.sec = d["header"]["stamp"]["sec"]
    msg.header.stamp.nanosec = d["header"]["stamp"]["nanosec"]
    for st in d["status"]:
        s = DiagnosticStatus(level=bytes([st["level"]]), name=st["name"], message=st["message"],
                             hardware_id=st["hardware_id"])
        s.values = [KeyValue(key=kv["key"], value=kv["value"]) for kv in st["values"]]
        msg.status.append(s)
    return msg


class FfcStatusNode(Node):
    def __init__(self) -> None:
        super().__init__("thermal_status")
        p = {name: self.declare_parameter(name, default).value for name, default in (
            ("image_topic", "image_raw"), ("status_topic", "status"), ("camera_name", "thermal"),
            ("hardware_id", ""), ("telemetry_rows", 2), ("telemetry_location", "bottom"),
            ("publish_period_s", 0.0))}
        # the clock offset now, as close to usb_cam's start (same launch) as this node gets: host clock
        # steps after it are in every status message (firmware/device/clockstep.py)
        clock = ClockSteps()
        self.tracker = StatusTracker(p["camera_name"], str(p["hardware_id"]), int(p["telemetry_rows"]),
                                     p["telemetry_location"], float(p["publish_period_s"]), clock)
        self.pub = self.create_publisher(DiagnosticArray, p["status_topic"], 10)
        self.create_subscription(Image, p["image_topic"], self.on_image, qos_profile_sensor_data)
        self.get_logger().info(f"FFC status of {p['image_topic']} -> {p['status_topic']} "
                               f"({p['telemetry_rows']} telemetry rows, {p['telemetry_location']})")

    def on_image(self, img: Image) -> None:
        stamp = img.header.stamp.sec * 1_000_000_000 + img.header.stamp.nanosec
        out = self.tracker.on_frame(stamp, memoryview(img.data), img.height, img.step)
        if out is not None:
            self.pub.publish(to_msg(out))


def main(argv: list[str] | None = None) -> int:
    return spin(FfcStatusNode, argv)


if __name__ == "__main__":
    sys.exit(main())
