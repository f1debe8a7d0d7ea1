"""ROS 2 node: each camera's frame rate and status on /health/<camera>/frequency and /status.

Runs in the health_topics container (compose.yaml), from config/health.yaml:

    python3 -m firmware.device.health_node --ros-args --params-file /config/health.yaml

Subscribes to each camera's camera_info topic, publishes std_msgs/Float64 (Hz) and std_msgs/String
(OK, LOW, HIGH, NO DATA) once per `publish_period_s`. The decisions are in
:mod:`firmware.device.health`; this module only moves messages, and imports rclpy: device only.
"""
from __future__ import annotations

import sys
import time

from rclpy.node import Node
from rclpy.qos import qos_profile_sensor_data
from sensor_msgs.msg import CameraInfo
from std_msgs.msg import Float64, String

from firmware.device.health import CameraHealth
from firmware.device.rosnode import spin


class HealthNode(Node):
    def __init__(self) -> None:
        super().__init__("health")
        cameras = self.declare_parameter("cameras", [""]).value
        rate = float(self.declare_parameter("expected_hz", 30.0).value)
        period = float(self.declare_parameter("publish_period_s", 1.0).value)
        self.cams = {}
        for cam in cameras:
            info = self.declare_parameter(f"{cam}.camera_info_topic", "").value
            freq = self.declare_parameter(f"{cam}.frequency_topic", "").value
            status = self.declare_parameter(f"{cam}.status_topic", "").value
            health = CameraHealth(cam, rate)
            self.create_subscription(CameraInfo, info, lambda _msg, h=health: h.on_frame(time.monotonic()),
                                     qos_profile_sensor_data)
            self.cams[cam] = (health, self.create_publisher(Float64, freq, 10), self.create_publisher(String, status, 10))
        self.create_timer(period, self.publish)

    def publish(self) -> None:
        now = time.monotonic()
        for health, freq, status in self.cams.values():
            hz, state = health.report(now)
            freq.publish(Float64(data=float(hz)))
            status.publish(String(data=state))


def main(argv: list[str] | None = None) -> int:
    return spin(HealthNode, argv)


if __name__ == "__main__":
    sys.exit(main())
