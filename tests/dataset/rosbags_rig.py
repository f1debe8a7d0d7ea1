"""Recordings of a rig written with the rosbags library (an independent ROS 2 bag writer, not this project's
simulator), with the truth of which trigger pulse exposed every frame.

The timeline is built here from first principles and shares no code with platform_tools.sim: a trigger
every 1/30 s; pulses missing from every camera; per camera host drops; each Boson stamped
``latency_ms`` after its trigger with its own jitter; an FFC freezing a Boson's image for a range of
triggers; host clock steps on the ZED clock (ZED images and IMU), on the thermal clock, or on both.
Images are tiny (ZED 32x20, Boson 40x32: the calibrated aspect ratios) so the tests stay fast.

With ``telemetry`` on, every Boson frame carries two telemetry rows below its image, written here from the
documented format (``../shared/reference/boson-protocol.md``: status word at byte 76, frame counter at byte 84,
frame count at the last FFC at byte 88, big-endian) with ``struct``, not with the project's encoder. The
counter counts the pulses the camera received: host drops advance it, pulses that never came do not.

Topic names come from a layout (the project's: the rig's ``on_device.topics``; the released stack's:
``UPSTREAM`` below, as its topic_list.yaml spells them).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import struct

import cv2
import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

PERIOD_NS = 1e9 / 30
T0_NS = 1_700_000_000 * 1_000_000_000
IMU_PERIOD_NS = 5_000_000
ZED_SIZE = (32, 20)        # W, H: 1920x1200 / 60
THERMAL_SIZE = (40, 32)    # 640x512 / 16
TRANSPORT_NS = 6_000_000   # log time after the stamp
TELEMETRY_ROWS = 2         # rig.yaml on_device.thermal_telemetry_rows
#: the frame counters when the recording starts (a Boson counts from its boot)
COUNTER_BASE = {"thermal_left": 4_294_967_200, "thermal_right": 812_345}   # the left one wraps (u32)
#: the FFC state's place in the status word: bits 4-5 (the project's assumption, platform_tools/boson/telemetry.py;
#: no public source gives it), values of bosonGetFfcStatus (2: in progress)
FFC_STATE_SHIFT = 4

#: the released TartanRGBT stack's topics (upstream-tartanrgbt.md): the ones a reader needs, and the
#: extra ones its bags also carry
UPSTREAM = {"zed_left": "/zed/zed_node/left_raw/image_raw_color", "zed_right": "/zed/zed_node/right_raw/image_raw_color",
            "zed_left_info": "/zed/zed_node/left_raw/camera_info", "zed_right_info": "/zed/zed_node/right_raw/camera_info",
            "zed_imu": "/zed/zed_node/imu/data", "thermal_left": "/thermal_left/image",
            "thermal_right": "/thermal_right/image", "thermal_left_info": "/thermal_left/camera_info",
            "thermal_right_info": "/thermal_right/camera_info", "thermal_left_status": "/thermal_left/ffc_status",
            "thermal_right_status": "/thermal_right/ffc_status"}
UPSTREAM_EXTRA = ("/zed/zed_node/status/heartbeat", "/health/thermal_left/frequency", "/zed/robot_description")


def project_layout(rig) -> dict[str, str]:
    t = rig.desc.on_device.topics
    return {s: getattr(t, s) for s in ("zed_left", "zed_right", "zed_depth", "zed_imu", "thermal_left",
                                       "thermal_right", "thermal_left_status", "thermal_right_status")}


@dataclass
class Spec:
    triggers: int = 150
    latency_ms: dict = field(default_factory=lambda: {"thermal_left": 10.0, "thermal_right": 20.0})
    #: trigger pulses that never came (missing in every camera)
    missing: tuple = (20, 21, 55, 90, 121)
    drop: float = 0.02
    #: camera -> (first, last) trigger of its FFC: the image frozen on the frame before
    ffc: dict = field(default_factory=lambda: {"thermal_left": (70, 84)})
    #: (trigger at which the host clock steps, size in ms, "zed" | "thermal" | "all")
    steps: tuple = ()
    status: str | None = "diagnostic"      # "diagnostic" | "bool" | "uint8" (a type nobody publishes) | None
    extra: bool = False                    # the upstream topics a reader ignores (UPSTREAM_EXTRA, /diagnostics)
    zed_compressed: bool = True            # the project's ZED topics are JPEG; upstream's raw bgra8
    depth: bool = True
    camera_info: bool = False
    #: Boson telemetry rows (frame counter, FFC state) below each thermal image
    telemetry: bool = False
    #: camera -> trigger pulses that one Boson alone never received (the ZED has those frames)
    boson_missed: dict = field(default_factory=dict)
    imu: bool = True
    #: the status message's log time after its image's (negative: logged before the image reached the recorder)
    status_log_after_ns: int = 1_000_000
    #: frames by which the telemetry's FFC state leads the frozen image (a camera flagging the FFC early)
    telemetry_ffc_lead: int = 0
    #: the telemetry line delivered with the bytes of every 16-bit word swapped (a layout this reader assumes wrongly)
    telemetry_word_swapped: bool = False
    seed: int = 0
    #: camera -> function of the trigger number giving that frame's uint16 image (default: noise of THERMAL_SIZE)
    thermal_px: dict = field(default_factory=dict)


def _stepped(true_ns: np.ndarray, steps, clock: str, period_ns: float = PERIOD_NS) -> np.ndarray:
    out = true_ns.astype(np.int64).copy()
    for at, ms, on in steps:
        if on in (clock, "all"):
            out += np.where(true_ns >= T0_NS + at * period_ns - 2e6, int(ms * 1e6), 0).astype(np.int64)
    return out


def timeline(spec: Spec) -> dict:
    """Per stream: (trigger numbers, true stamps, host stamps); the IMU's true and host stamps."""
    rng = np.random.default_rng(spec.seed)
    k_all = np.array([k for k in range(spec.triggers) if k not in spec.missing])
    out = {}
    kz = k_all[rng.random(len(k_all)) > spec.drop]
    tz = T0_NS + kz * PERIOD_NS + rng.normal(0, 0.2e6, len(kz))
    out["zed_left"] = (kz, tz, _stepped(tz, spec.steps, "zed"))
    for cam in ("thermal_left", "thermal_right"):
        k_cam = np.array([k for k in k_all if k not in spec.boson_missed.get(cam, ())]) \
            if spec.boson_missed.get(cam) else k_all
        k = k_cam[rng.random(len(k_cam)) > spec.drop]
        t = T0_NS + k * PERIOD_NS + spec.latency_ms[cam] * 1e6 + rng.normal(0, 0.6e6, len(k))
        out[cam] = (k, t, _stepped(t, spec.steps, "thermal"))
    ti = T0_NS - 1e8 + np.arange(int((spec.triggers * PERIOD_NS + 2e8) / IMU_PERIOD_NS)) * IMU_PERIOD_NS
    out["zed_imu"] = (None, ti, _stepped(ti, spec.steps, "zed"))
    return out


def telemetry_line(counter: int, ffc_state: int, ffc_counter: int, nbytes: int) -> bytes:
    """A Boson telemetry line as the reference describes it (big-endian fields at bytes 76, 84, 88)."""
    line = bytearray(nbytes)
    struct.pack_into(">Q", line, 76, ffc_state << FFC_STATE_SHIFT)
    struct.pack_into(">I", line, 84, counter % (1 << 32))
    struct.pack_into(">I", line, 88, ffc_counter % (1 << 32))
    return bytes(line)


def counters(spec: Spec, cam: str) -> dict[int, int]:
    """Trigger pulse -> the camera's frame counter at it: one count per pulse the camera received."""
    out, c = {}, COUNTER_BASE[cam]
    for k in range(spec.triggers):
        if k in spec.missing or k in spec.boson_missed.get(cam, ()):
            continue
        out[k] = c
        c += 1
    return out


def _header(ts, stamp_ns: int, frame_id: str):
    Time = ts.types["builtin_interfaces/msg/Time"]
    Header = ts.types["std_msgs/msg/Header"]
    return Header(stamp=Time(sec=int(stamp_ns // 1_000_000_000), nanosec=int(stamp_ns % 1_000_000_000)),
                  frame_id=frame_id)


def _image(ts, stamp, frame_id, px: np.ndarray, encoding: str):
    h, w = px.shape[:2]
    data = np.ascontiguousarray(px).view(np.uint8).reshape(-1)
    return ts.types["sensor_msgs/msg/Image"](header=_header(ts, stamp, frame_id), height=h, width=w,
                                             encoding=encoding, is_bigendian=0, step=data.size // h, data=data)


def camera_info(ts, stamp, frame_id, size, fx, fy, cx, cy, d=(0.0, 0.0, 0.0, 0.0, 0.0)):
    RegionOfInterest = ts.types["sensor_msgs/msg/RegionOfInterest"]
    return ts.types["sensor_msgs/msg/CameraInfo"](
        header=_header(ts, stamp, frame_id), height=size[1], width=size[0], distortion_model="plumb_bob",
        d=np.array(d, float), k=np.array([fx, 0, cx, 0, fy, cy, 0, 0, 1], float),
        r=np.eye(3).reshape(-1), p=np.array([fx, 0, cx, 0, 0, fy, cy, 0, 0, 0, 1, 0], float),
        binning_x=0, binning_y=0, roi=RegionOfInterest(x_offset=0, y_offset=0, height=0, width=0, do_rectify=False))


def write(path: Path, spec: Spec, topics: dict[str, str], storage: str = "mcap",
          infos: dict[str, object] | None = None) -> dict:
    """Write the bag folder ``path``; return the truth: per stream, host stamp -> trigger number, and
    per thermal camera the triggers of its frozen (FFC) frames."""
    ts = get_typestore(Stores.ROS2_HUMBLE)
    rng = np.random.default_rng(spec.seed + 100)
    tl = timeline(spec)
    msgs: list[tuple[int, str, str, object]] = []     # (log ns, topic, type, message)
    truth = {"trigger_of": {}, "ffc_triggers": {}, "latency_ms": dict(spec.latency_ms), "steps": list(spec.steps)}
    kz, tz, hz = tl["zed_left"]
    zed_type = "sensor_msgs/msg/CompressedImage" if spec.zed_compressed else "sensor_msgs/msg/Image"
    for k, t, h in zip(kz, tz, hz):
        log = int(t) + TRANSPORT_NS
        for side in ("left", "right"):
            bgr = rng.integers(0, 255, (ZED_SIZE[1], ZED_SIZE[0], 3), dtype=np.uint8)
            fid = f"zed_{side}_camera_optical_frame"
            if spec.zed_compressed:
                jpg = cv2.imencode(".jpg", bgr)[1].reshape(-1)
                m = ts.types["sensor_msgs/msg/CompressedImage"](header=_header(ts, int(h), fid), format="jpeg",
                                                                 data=jpg)
            else:
                bgra = np.dstack([bgr, np.full(bgr.shape[:2], 255, np.uint8)])
                m = _image(ts, int(h), fid, bgra, "bgra8")
            msgs.append((log, topics[f"zed_{side}"], zed_type, m))
        if spec.depth:
            msgs.append((log, topics["zed_depth"], "sensor_msgs/msg/Image",
                         _image(ts, int(h), "zed_left_camera_optical_frame",
                                np.full((ZED_SIZE[1], ZED_SIZE[0]), 3.0, np.float32), "32FC1")))
        for name in ("zed_left", "zed_right") + (("zed_depth",) if spec.depth else ()):
            truth["trigger_of"].setdefault(name, {})[int(h)] = int(k)
    for cam in ("thermal_left", "thermal_right"):
        k_, t_, h_ = tl[cam]
        first, last = spec.ffc.get(cam, (-1, -2))
        truth["ffc_triggers"][cam] = [int(k) for k in k_ if first <= k <= last]
        frozen_px = None
        count = counters(spec, cam)
        ffc_counter = count.get(first, COUNTER_BASE[cam]) if first >= 0 else COUNTER_BASE[cam] - 900
        for k, t, h in zip(k_, t_, h_):
            in_ffc = first <= k <= last
            if in_ffc and frozen_px is not None:
                px = frozen_px
            else:
                px = (spec.thermal_px[cam](int(k)) if cam in spec.thermal_px else
                      (20000 + rng.normal(0, 300, (THERMAL_SIZE[1], THERMAL_SIZE[0]))).astype(np.uint16))
                frozen_px = px
            log = int(t) + TRANSPORT_NS
            if spec.telemetry:     # the rows below the image: the line's bytes as the frame buffer holds them
                nbytes = TELEMETRY_ROWS * THERMAL_SIZE[0] * 2
                lead = spec.telemetry_ffc_lead
                flagged = first - lead <= k <= last - lead
                line = telemetry_line(count[int(k)], 2 if flagged else (3 if k > last - lead >= 0 else 0),
                                      ffc_counter if k >= first >= 0 else COUNTER_BASE[cam] - 900, nbytes)
                if spec.telemetry_word_swapped:
                    line = bytes(np.frombuffer(line, "<u2").byteswap().tobytes())
                px = np.vstack([px, np.frombuffer(line, "<u2").reshape(TELEMETRY_ROWS, THERMAL_SIZE[0])])
            msgs.append((log, topics[cam], "sensor_msgs/msg/Image", _image(ts, int(h), f"{cam}_optical", px, "mono16")))
            truth["trigger_of"].setdefault(cam, {})[int(h)] = int(k)
            if spec.telemetry:
                truth.setdefault("counter_of", {}).setdefault(cam, {})[int(h)] = count[int(k)]
            if spec.status == "diagnostic":
                kv = ts.types["diagnostic_msgs/msg/KeyValue"]
                st = ts.types["diagnostic_msgs/msg/DiagnosticStatus"](
                    level=bytes([1 if in_ffc else 0])[0], name=cam, message="FFC in progress" if in_ffc else "",
                    hardware_id="93588", values=[kv(key="ffc_status", value="2" if in_ffc else "0")])
                msgs.append((log + spec.status_log_after_ns, topics[f"{cam}_status"], "diagnostic_msgs/msg/DiagnosticArray",
                             ts.types["diagnostic_msgs/msg/DiagnosticArray"](header=_header(ts, int(h), ""),
                                                                             status=[st])))
            elif spec.status == "bool":
                msgs.append((log + spec.status_log_after_ns, topics[f"{cam}_status"], "std_msgs/msg/Bool",
                             ts.types["std_msgs/msg/Bool"](data=bool(in_ffc))))
            elif spec.status == "uint8":
                msgs.append((log + spec.status_log_after_ns, topics[f"{cam}_status"], "std_msgs/msg/UInt8",
                             ts.types["std_msgs/msg/UInt8"](data=2 if in_ffc else 0)))
    _, ti, hi = tl["zed_imu"]
    V3, Q = ts.types["geometry_msgs/msg/Vector3"], ts.types["geometry_msgs/msg/Quaternion"]
    for t, h in zip(ti, hi) if spec.imu else ():
        msgs.append((int(t) + 1_000_000, topics["zed_imu"], "sensor_msgs/msg/Imu", ts.types["sensor_msgs/msg/Imu"](
            header=_header(ts, int(h), "zed_imu_link"), orientation=Q(x=0.0, y=0.0, z=0.0, w=1.0),
            orientation_covariance=np.zeros(9), angular_velocity=V3(x=0.0, y=0.0, z=0.0),
            angular_velocity_covariance=np.zeros(9), linear_acceleration=V3(x=0.0, y=0.0, z=9.81),
            linear_acceleration_covariance=np.zeros(9))))
    if spec.extra:
        msgs += _extra(ts, tz)
    for topic, msg in (infos or {}).items():
        msgs.append((T0_NS, topic, "sensor_msgs/msg/CameraInfo", msg))
    msgs.sort(key=lambda m: m[0])
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer(Path(path), version=8, storage_plugin=plugin) as w:
        conns = {}
        for log, topic, typ, msg in msgs:
            if topic not in conns:
                conns[topic] = w.add_connection(topic, typ, typestore=ts)
            w.write(conns[topic], log, ts.serialize_cdr(msg, typ))
    return truth


#: a stand-in for zed_msgs/msg/HeartBeat (a type outside rosbags' store, as a real bag's would be)
HEARTBEAT_MSG = "uint64 beat_count\nstring node_ns\nstring full_name\nstring camera_sn\n"


def _extra(ts, tz) -> list:
    """Messages on the upstream topics a reader must ignore: heartbeat, health frequency, robot description,
    /diagnostics (a DiagnosticArray that is no camera's FFC status)."""
    from rosbags.typesys import get_types_from_msg
    ts.register(get_types_from_msg(HEARTBEAT_MSG, "zed_msgs/msg/HeartBeat"))
    hb, f32, s = ts.types["zed_msgs/msg/HeartBeat"], ts.types["std_msgs/msg/Float32"], ts.types["std_msgs/msg/String"]
    beat, freq, desc = UPSTREAM_EXTRA
    out = [(T0_NS, desc, "std_msgs/msg/String", s(data="<robot name='zedx'/>"))]
    kv = ts.types["diagnostic_msgs/msg/KeyValue"]
    for i, t in enumerate(tz[::10]):
        out.append((int(t) + 2_000_000, beat, "zed_msgs/msg/HeartBeat",
                     hb(beat_count=i, node_ns="/zed", full_name="/zed/zed_node", camera_sn="40000001")))
        out.append((int(t) + 3_000_000, freq, "std_msgs/msg/Float32", f32(data=30.0)))
        st = ts.types["diagnostic_msgs/msg/DiagnosticStatus"](level=0, name="zed", message="ok", hardware_id="zed",
                                                              values=[kv(key="ffc_status", value="2")])
        out.append((int(t) + 4_000_000, "/diagnostics", "diagnostic_msgs/msg/DiagnosticArray",
                    ts.types["diagnostic_msgs/msg/DiagnosticArray"](header=_header(ts, int(t), ""), status=[st])))
    return out
