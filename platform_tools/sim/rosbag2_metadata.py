"""A bag folder's ``metadata.yaml`` and each channel's offered QoS, as rosbag2 (humble) writes them.

rosbag2 and the rosbags library open a bag folder from ``metadata.yaml``: for every topic its
``type`` (``sensor_msgs/msg/Image``), ``serialization_format`` (``cdr``) and the QoS profiles its
publishers offered (a YAML string in metadata version 5, humble's, the ROS 2 release the rig runs).
rosbag2's MCAP storage also writes that string into each channel's metadata under
``offered_qos_profiles``. Pure functions: dicts and strings in, dicts and strings out.
"""
from __future__ import annotations

import yaml

#: rosbag2 humble writes metadata version 5
METADATA_VERSION = 5
STORAGE_ID = "mcap"
SERIALIZATION = "cdr"
#: the channel metadata key rosbag2_storage_mcap writes the QoS under
QOS_KEY = "offered_qos_profiles"

#: rmw's enums, as rosbag2 humble serialises them (integers)
HISTORY_UNKNOWN = 3          # rosbag2 records the offered history as unknown
RELIABILITY_RELIABLE, RELIABILITY_BEST_EFFORT = 1, 2
DURABILITY_TRANSIENT_LOCAL, DURABILITY_VOLATILE = 1, 2
LIVELINESS_AUTOMATIC = 1
#: rmw's "infinite" duration, as rosbag2 writes it
INFINITE = {"sec": 9223372036, "nsec": 854775807}


def qos_profile(reliability: int = RELIABILITY_RELIABLE, durability: int = DURABILITY_VOLATILE) -> dict:
    """One offered QoS profile as rosbag2 humble records it (history unknown, depth 0: what a
    recorder learns from discovery). The defaults are rclcpp's default publisher QoS (reliable,
    volatile), which the ZED wrapper (its default ``qos_reliability``), usb_cam and the FFC status
    node offer; an estimate until read from a real recording's metadata."""
    return {"history": HISTORY_UNKNOWN, "depth": 0, "reliability": reliability, "durability": durability,
            "deadline": dict(INFINITE), "lifespan": dict(INFINITE), "liveliness": LIVELINESS_AUTOMATIC,
            "liveliness_lease_duration": dict(INFINITE), "avoid_ros_namespace_conventions": False}


def qos_yaml(profiles: list[dict]) -> str:
    """The ``offered_qos_profiles`` string: a YAML list of profiles (one per publisher)."""
    return yaml.safe_dump(profiles, sort_keys=False).strip()


def metadata(files: list[dict], topics: dict[str, dict]) -> dict:
    """The content of ``metadata.yaml``.

    ``files``: per file, ``path`` (relative), ``start_ns``, ``end_ns``, ``messages``;
    ``topics``: topic -> ``{"type": "pkg/msg/Type", "messages": n, "qos": [profile, ...]}``."""
    start = min(f["start_ns"] for f in files)
    end = max(f["end_ns"] for f in files)
    return {"rosbag2_bagfile_information": {
        "version": METADATA_VERSION, "storage_identifier": STORAGE_ID,
        "duration": {"nanoseconds": end - start}, "starting_time": {"nanoseconds_since_epoch": start},
        "message_count": sum(t["messages"] for t in topics.values()),
        "topics_with_message_count": [
            {"topic_metadata": {"name": name, "type": t["type"], "serialization_format": SERIALIZATION,
                                "offered_qos_profiles": qos_yaml(t["qos"])},
             "message_count": t["messages"]} for name, t in topics.items()],
        "compression_format": "", "compression_mode": "",
        "relative_file_paths": [f["path"] for f in files],
        "files": [{"path": f["path"], "starting_time": {"nanoseconds_since_epoch": f["start_ns"]},
                   "duration": {"nanoseconds": f["end_ns"] - f["start_ns"]}, "message_count": f["messages"]}
                  for f in files]}}


def dump(meta: dict) -> str:
    return yaml.safe_dump(meta, sort_keys=False)
