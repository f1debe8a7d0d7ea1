"""Write a simulated recording as the rig would: a rosbag2 folder with an MCAP of ROS 2 CDR messages
(the rig's topics and frame ids, each channel with its offered QoS), its metadata.yaml as rosbag2
writes it (:mod:`.rosbag2_metadata`: rosbag2 and rosbags open the folder), and truth.json listing what
was injected. The thermal status is what the FFC status node publishes
(:class:`firmware.device.ffc_status.StatusTracker`, fed each received frame's telemetry)."""
from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
from mcap.writer import CompressionType, Writer as McapWriter
from mcap_ros2._dynamic import serialize_dynamic

from platform_tools.rig import atomic
from platform_tools.rig.cameras import imagersize
from platform_tools.rig.progress import progress
from ..rig import Rig
from platform_tools.boson import telemetry
from firmware.device.ffc_status import StatusTracker
from . import geometry, msgs, rosbag2_metadata
from .timeline import NS, SimParams, Timeline, build, ffc_state

LATENCY_NS = {"image": 6_000_000, "imu": 1_000_000, "status": 2_000_000}
#: the simulated Bosons' serial numbers (bosonGetCameraSN) when the rig's are still placeholders (null)
SIM_SERIALS = {"left": 900001, "right": 900002}
MESSAGE_TYPES = ("sensor_msgs/Image", "sensor_msgs/CompressedImage", "sensor_msgs/Imu",
                 "diagnostic_msgs/DiagnosticArray")


class BagWriter:
    """One MCAP as rosbag2_storage_mcap writes it: ROS 2 schemas, CDR messages, and every channel
    carrying its publishers' offered QoS in its metadata; counts what it wrote for metadata.yaml."""

    def __init__(self, f):
        self.w = McapWriter(f, compression=CompressionType.ZSTD)
        self.w.start(profile="ros2", library="rgbt-rig simulate-rig")
        self.schemas, self.encoders, self.channels = {}, {}, {}
        self.counts: dict[str, int] = {}
        self.types: dict[str, str] = {}
        self.qos = [rosbag2_metadata.qos_profile()]
        for name in MESSAGE_TYPES:
            ros_name, text = msgs.msgdef(name)
            self.schemas[name] = self.w.register_schema(ros_name, "ros2msg", text.encode())
            self.encoders[name] = serialize_dynamic(ros_name, text)[ros_name]

    def put(self, topic: str, typ: str, msg: dict, log_ns: int) -> None:
        if topic not in self.channels:
            self.channels[topic] = self.w.register_channel(
                topic, "cdr", self.schemas[typ], {rosbag2_metadata.QOS_KEY: rosbag2_metadata.qos_yaml(self.qos)})
            self.types[topic] = msgs.msgdef(typ)[0]
        n = self.counts.get(topic, 0)
        self.w.add_message(self.channels[topic], log_ns, self.encoders[typ](msg), log_ns, n)
        self.counts[topic] = n + 1

    def finish(self) -> None:
        self.w.finish()

    def topics(self) -> dict[str, dict]:
        return {t: {"type": self.types[t], "messages": c, "qos": self.qos} for t, c in self.counts.items()}


def boson_serial(rig: Rig, side: str) -> int:
    serial = getattr(rig.desc.sensors.thermal, side).serial
    return int(serial) if serial is not None else SIM_SERIALS[side]


def _sizes(rig: Rig, scale: float) -> dict[str, tuple[int, int]]:
    zed = rig.camera_model(rig.desc.sensors.zed_x.camera_model)
    th = rig.camera_model(rig.desc.sensors.thermal.camera_model)
    down = rig.desc.on_device.zed_pub_downscale_factor
    return {"zed": (max(8, int(zed.width_px / down * scale)), max(8, int(zed.height_px / down * scale))),
            "thermal": (max(8, int(th.width_px * scale)), max(8, int(th.height_px * scale)))}


#: the Bosons' frame counters when the recording starts (they count every trigger pulse since boot),
#: and how many frames before that their last FFC ran
COUNTER_BASE = {"thermal_left": 183_000, "thermal_right": 179_500}
BOOT_FFC_FRAMES_AGO = 2_700


class BosonTelemetry:
    """What each simulated Boson writes in its telemetry rows: its frame counter (one per trigger
    pulse, whether or not the host receives the frame), the FFC state of the timeline's truth (the
    same as the status topic), and the counter at the start of its last FFC."""

    def __init__(self, tl: Timeline, rows: int, width: int):
        self.tl, self.rows, self.width_px = tl, rows, width
        self.enabled = rows > 0 and rows * width * 2 >= telemetry.MIN_LINE_BYTES
        period_ns = NS / tl.rate_hz
        self.ffc_start_pulse: dict[str, list[int]] = {}
        for e in tl.ffc:   # the first pulse captured during the FFC (true clock): the first frozen frame
            cam = e["camera"]
            frozen = [f.index for f in tl.frames if f.camera == cam and f.frozen
                      and e["start_ns"] - period_ns <= f.stamp_ns - self._step(f.stamp_ns) < e["end_ns"] + period_ns]
            first = (e["start_ns"] - tl.params.start_ns - tl.offsets_ms[cam] * 1e6) / period_ns
            self.ffc_start_pulse.setdefault(cam, []).append(min(frozen) if frozen else int(np.ceil(first)))

    def _step(self, host_ns: int) -> int:
        step = self.tl.clock_step
        return step["step_ns"] if host_ns >= step["true_ns"] + step["step_ns"] else 0

    def line(self, camera: str, index: int, stamp_ns: int) -> bytes:
        base = COUNTER_BASE[camera]
        started = [k for k in self.ffc_start_pulse.get(camera, []) if k <= index]
        ffc_frame = base + max(started) if started else base - BOOT_FFC_FRAMES_AGO
        return telemetry.encode_line(base + index, ffc_state(self.tl, camera, stamp_ns), ffc_frame,
                                     max(self.rows * 2 * self.width_px, telemetry.MIN_LINE_BYTES))


def _events(tl: Timeline) -> list[tuple[int, str, object]]:
    """Every message's log time: frames, IMU samples, and the status the FFC node publishes for
    each thermal frame it receives (stamped as the frame, logged after it)."""
    ev = [(f.stamp_ns + LATENCY_NS["image"], "frame", f) for f in tl.frames]
    ev += [(f.stamp_ns + LATENCY_NS["image"] + LATENCY_NS["status"], "status", f)
           for f in tl.frames if f.camera.startswith("thermal")]
    ev += [(t + LATENCY_NS["imu"], "imu", t) for t in tl.imu_stamps_ns]
    ev.sort(key=lambda e: (e[0], e[1]))
    return ev


def simulate(rig: Rig, out: Path, params: SimParams, scale: float = 0.25) -> dict:
    tl = build(rig, params)
    topics = rig.desc.on_device.topics
    sizes = _sizes(rig, scale)
    rng = np.random.default_rng(params.seed + 1)
    with atomic.OutputDir(out) as stage:
        bag = stage / "bag"
        bag.mkdir()
        with open(bag / "bag_0.mcap", "wb") as f:
            w = BagWriter(f)
            put = w.put
            last_thermal: dict[str, np.ndarray] = {}
            events = _events(tl)
            renderer = geometry.SceneRenderer(rig, sizes)
            tele = BosonTelemetry(tl, rig.desc.on_device.thermal_telemetry_rows, sizes["thermal"][0])
            trackers = {f"thermal_{side}": StatusTracker(f"thermal_{side}", str(boson_serial(rig, side)), tele.rows)
                        for side in ("left", "right")}
            for log_ns, kind, item in progress(events, desc="simulate-rig", unit="msg"):
                if kind == "frame":
                    t_s = (item.index / tl.rate_hz)
                    side = item.camera.split("_")[1]
                    frame_id = f"{item.camera}_optical" if item.camera.startswith("thermal") else \
                        f"{rig.desc.on_device.zed_camera_name}_{side}_camera_optical_frame"
                    if item.camera.startswith("thermal"):
                        if item.frozen and item.camera in last_thermal:
                            px = last_thermal[item.camera]
                        else:
                            r, boxes = renderer.render(item.camera, t_s)
                            raw = geometry.counts_from_c(geometry.temperature_c(r, boxes, renderer.scene))
                            px = np.clip(raw + rng.normal(0, 8, raw.shape), 0, 65535).astype(np.uint16)
                            last_thermal[item.camera] = px
                        if tele.enabled:   # the image may be frozen (FFC), the telemetry never is
                            px = np.vstack([px, np.zeros((tele.rows, px.shape[1]), np.uint16)])
                            px = telemetry.write_into(px, tele.line(item.camera, item.index, item.stamp_ns),
                                                      tele.rows)
                        put(getattr(topics, item.camera), "sensor_msgs/Image",
                            msgs.image(item.stamp_ns, frame_id, px, "mono16"), log_ns)
                    else:
                        r, boxes = renderer.render(item.camera, t_s)
                        bgr = geometry.colour(r, boxes, renderer.scene)
                        bgr = np.clip(bgr + rng.normal(0, 2, bgr.shape), 0, 255).astype(np.uint8)
                        ok, jpg = cv2.imencode(".jpg", bgr, [cv2.IMWRITE_JPEG_QUALITY, 90])
                        put(getattr(topics, item.camera), "sensor_msgs/CompressedImage",
                            msgs.compressed_image(item.stamp_ns, frame_id, jpg.tobytes()), log_ns)
                        if side == "left":
                            put(topics.zed_depth, "sensor_msgs/Image",
                                msgs.image(item.stamp_ns, frame_id, geometry.zed_depth_m(r, renderer.scene),
                                           "32FC1"), log_ns)
                elif kind == "imu":
                    put(topics.zed_imu, "sensor_msgs/Imu",
                        msgs.imu(item, f"{rig.desc.on_device.zed_camera_name}_imu_link",
                                 rng.normal(0, 0.01, 3), (0.0, 0.0, 9.81) + rng.normal(0, 0.05, 3)), log_ns)
                else:   # the FFC status node's message for this frame (it reads the same telemetry)
                    tel = telemetry.decode_line(tele.line(item.camera, item.index, item.stamp_ns))
                    status = trackers[item.camera].on_telemetry(item.stamp_ns, tel)
                    if status is not None:
                        put(getattr(topics, f"{item.camera}_status"), "diagnostic_msgs/DiagnosticArray", status,
                            log_ns)
            w.finish()
        start, end = events[0][0], events[-1][0]
        counts = w.counts
        (bag / "metadata.yaml").write_text(rosbag2_metadata.dump(rosbag2_metadata.metadata(
            [{"path": "bag_0.mcap", "start_ns": start, "end_ns": end, "messages": sum(counts.values())}],
            w.topics())))
        truth = tl.truth() | {"rig_hash": rig.hash, "topics": counts, "image_sizes": sizes, "scale": scale,
                              "boson_serials": {s: boson_serial(rig, s) for s in ("left", "right")},
                              "telemetry": {"rows": tele.rows if tele.enabled else 0, "location": "bottom",
                                            "frame_counter_base": COUNTER_BASE,
                                            "ffc_start_pulse": tele.ffc_start_pulse},
                              "scene": renderer.scene,
                              "cameras": {k: {"frame": renderer.FRAMES[k], "lensmodel": c.intrinsics()[0],
                                              "intrinsics": c.intrinsics()[1].tolist(), "size": list(imagersize(c))}
                                          for k, c in renderer.cams.items()},
                              "units": "times in ns since the epoch (true clock unless noted); offsets in ms "
                                       "after the trigger; dropped: trigger pulse numbers"}
        (stage / "truth.json").write_text(json.dumps(truth, indent=2) + "\n")
    return truth
