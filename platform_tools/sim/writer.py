"""Write a simulated recording as the rig would: a rosbag2 folder with an MCAP of ROS 2 CDR messages
(the rig's topics and frame ids), its metadata.yaml, and truth.json listing what was injected."""
from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import yaml
from mcap_ros2.writer import Writer

from platform_tools.rig import atomic
from platform_tools.rig.cameras import imagersize
from platform_tools.rig.progress import progress
from ..rig import Rig
from platform_tools.boson import telemetry
from . import geometry, msgs
from .timeline import NS, SimParams, Timeline, build, ffc_state

LATENCY_NS = {"image": 6_000_000, "imu": 1_000_000, "status": 2_000_000}


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
                                     self.rows * 2 * self.width_px)


def _events(tl: Timeline) -> list[tuple[int, str, object]]:
    ev = [(f.stamp_ns + LATENCY_NS["image"], "frame", f) for f in tl.frames]
    ev += [(t + LATENCY_NS["imu"], "imu", t) for t in tl.imu_stamps_ns]
    ev += [(t + LATENCY_NS["status"], "status", t) for t in tl.status_ns]
    ev.sort(key=lambda e: (e[0], e[1]))
    return ev


def simulate(rig: Rig, out: Path, params: SimParams, scale: float = 0.25) -> dict:
    tl = build(rig, params)
    topics = rig.desc.on_device.topics
    sizes = _sizes(rig, scale)
    rng = np.random.default_rng(params.seed + 1)
    counts: dict[str, int] = {}
    with atomic.OutputDir(out) as stage:
        bag = stage / "bag"
        bag.mkdir()
        with open(bag / "bag_0.mcap", "wb") as f:
            w = Writer(f)
            schema = {n: w.register_msgdef(*msgs.msgdef(n)) for n in (
                "sensor_msgs/Image", "sensor_msgs/CompressedImage", "sensor_msgs/Imu",
                "diagnostic_msgs/DiagnosticArray")}
            last_thermal: dict[str, np.ndarray] = {}

            def put(topic: str, typ: str, msg: dict, log_ns: int) -> None:
                w.write_message(topic, schema[typ], msg, log_time=log_ns, publish_time=log_ns,
                                sequence=counts.get(topic, 0))
                counts[topic] = counts.get(topic, 0) + 1

            events = _events(tl)
            renderer = geometry.SceneRenderer(rig, sizes)
            tele = BosonTelemetry(tl, rig.desc.on_device.thermal_telemetry_rows, sizes["thermal"][0])
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
                else:
                    for side in ("left", "right"):
                        cam = f"thermal_{side}"
                        state = ffc_state(tl, cam, item)
                        put(getattr(topics, f"{cam}_status"), "diagnostic_msgs/DiagnosticArray",
                            msgs.diagnostic(item, cam, str(getattr(rig.desc.sensors.thermal, side).serial),
                                            {"ffc_status": state, "ffc_in_progress": int(state == 2)}), log_ns)
            w.finish()
        start, end = events[0][0], events[-1][0]
        (bag / "metadata.yaml").write_text(yaml.safe_dump({"rosbag2_bagfile_information": {
            "version": 5, "storage_identifier": "mcap", "relative_file_paths": ["bag_0.mcap"],
            "duration": {"nanoseconds": end - start}, "starting_time": {"nanoseconds_since_epoch": start},
            "message_count": sum(counts.values()),
            "topics_with_message_count": [{"topic_metadata": {"name": t, "serialization_format": "cdr"},
                                           "message_count": c} for t, c in counts.items()]}}, sort_keys=False))
        truth = tl.truth() | {"rig_hash": rig.hash, "topics": counts, "image_sizes": sizes, "scale": scale,
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
