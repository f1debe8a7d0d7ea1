"""Boson telemetry: decode the telemetry rows of a Y16 frame, and publish the FFC status from them.

- ``decode``  byte layout (offsets with their source, verify on hardware), decoder and the
              simulator's encoder: pure functions on bytes and numpy arrays
- ``status``  the publisher's pure part: frame in, DiagnosticArray (as a dict) out
- ``node``    the ROS 2 node (rclpy): imported on the device only, in the thermal container
"""
from .decode import (FFC_FRAME_OFFSET, FRAME_COUNTER_OFFSET, STATUS_OFFSET, Telemetry, TelemetryError,
                     decode_frame, decode_image_data, decode_line, encode_line, split_frame,
                     telemetry_rows_present, write_into)

__all__ = ["FFC_FRAME_OFFSET", "FRAME_COUNTER_OFFSET", "STATUS_OFFSET", "Telemetry", "TelemetryError",
           "decode_frame", "decode_image_data", "decode_line", "encode_line", "split_frame",
           "telemetry_rows_present", "write_into"]
