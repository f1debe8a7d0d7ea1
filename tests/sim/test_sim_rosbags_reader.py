"""The simulated bags open in rosbags (an independent rosbag2 reader) from their folder, as rosbag2 would
open them: metadata.yaml with every topic's type, serialization format and offered QoS; the status
messages as the FFC status node publishes them (firmware.device.ffc_status)."""
from __future__ import annotations

import pytest
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore

from platform_tools.sim.timeline import SimParams
from platform_tools.sim.writer import simulate

TS = get_typestore(Stores.ROS2_HUMBLE)
NODE_KEYS = {"ffc_status", "ffc_in_progress", "frame_counter", "frames_since_ffc", "missed_frames"}


@pytest.fixture(scope="module")
def bag(tmp_path_factory, rig):
    out = tmp_path_factory.mktemp("simbag") / "rec"
    truth = simulate(rig, out, SimParams(3.0, seed=4, drop_probability=0.02), scale=0.1)
    return rig, out / "bag", truth


@pytest.mark.slow
def test_rosbags_opens_the_folder_with_types_counts_and_qos(bag):
    rig, path, truth = bag
    t = rig.desc.on_device.topics
    with Reader(path) as r:
        types = {c.topic: c.msgtype for c in r.connections}
        counts = {c.topic: c.msgcount for c in r.connections}
        qos = {c.topic: c.ext.offered_qos_profiles for c in r.connections}
        assert types[t.thermal_left] == "sensor_msgs/msg/Image"
        assert types[t.zed_left] == "sensor_msgs/msg/CompressedImage"
        assert types[t.zed_imu] == "sensor_msgs/msg/Imu"
        assert types[t.thermal_right_status] == "diagnostic_msgs/msg/DiagnosticArray"
        assert counts == truth["topics"]
        assert all(len(q) == 1 and q[0].reliability.name == "RELIABLE" for q in qos.values())
        seen = {}
        for conn, _, raw in r.messages(connections=[c for c in r.connections if c.topic == t.thermal_left]):
            seen[conn.topic] = seen.get(conn.topic, 0) + 1
            if seen[conn.topic] == 1:
                img = TS.deserialize_cdr(raw, conn.msgtype)
                assert img.encoding == "mono16" and img.header.frame_id == "thermal_left_optical"
                assert len(img.data) == img.height * img.step and img.width == truth["image_sizes"]["thermal"][0]
        assert seen[t.thermal_left] == truth["topics"][t.thermal_left]


@pytest.mark.slow
def test_status_is_what_the_ffc_node_publishes(bag):
    rig, path, truth = bag
    t = rig.desc.on_device.topics
    with Reader(path) as r:
        conns = [c for c in r.connections if c.topic == t.thermal_left_status]
        arrays = [TS.deserialize_cdr(raw, c.msgtype) for c, _, raw in r.messages(connections=conns)]
    statuses = [a.status[0] for a in arrays]
    stamps = [a.header.stamp.sec * 1_000_000_000 + a.header.stamp.nanosec for a in arrays]
    ffc = next(e for e in truth["ffc"] if e["camera"] == "thermal_left")
    assert {s.hardware_id for s in statuses} == {str(truth["boson_serials"]["left"])}
    assert all({kv.key for kv in s.values} == NODE_KEYS for s in statuses)
    values = [{kv.key: kv.value for kv in s.values} for s in statuses]
    during = [s for s, v in zip(statuses, values) if v["ffc_status"] == "2"]
    assert len(during) >= 10 and {s.level for s in during} == {1}               # WARN during the FFC
    assert {s.level for s, v in zip(statuses, values) if v["ffc_status"] in ("0", "3")} <= {0}
    counters = [int(v["frame_counter"]) for v in values]
    assert counters == sorted(counters) and len(set(counters)) == len(counters)
    # a dropped frame shows as the node sees it: the counter skipped, missed_frames says by how much
    missed = sum(int(v["missed_frames"]) for v in values)
    assert missed == counters[-1] - counters[0] + 1 - len(counters) and missed >= 1
    period_ns = 1e9 / truth["rate_hz"]     # stamped as the frames: the FFC within a frame of the truth
    in_ffc = [t for t, v in zip(stamps, values) if v["ffc_status"] == "2"]
    assert abs(in_ffc[0] - ffc["start_ns"]) < period_ns and abs(in_ffc[-1] - ffc["end_ns"]) < period_ns
