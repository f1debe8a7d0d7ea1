"""Which topic layout a recording uses: which topic carries each rig stream.

Three layouts are known:

- ``project``: this rig's (``on_device.topics`` of the rig description, ``--set on_device.topics.*`` included);
- ``tartanrgbt``: the released TartanRGBT stack's (its ``topic_list.yaml``): raw ``bgra8`` ZED images with their
  factory ``camera_info``, ``/thermal_left/image`` with ``camera_info`` and ``ffc_status``; no depth topic;
- a topic map given with ``--topics FILE``: a small YAML mapping of stream names (:data:`KEYS`) to topics.

:func:`detect` picks, among the project's and the released stack's, the layout with the most image topics in the
recording (a tie goes to the project's); a recording holding the image topics of neither is refused in one line
naming it and the topics it holds. A topic map is used as given; its image topics must be in the recording.
Any other topic (``/diagnostics``, ``/tf``, ``/zed/zed_node/status/health``, ``/health/...``,
``/zed/robot_description``, ...) is ignored.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import yaml

#: streams whose messages are indexed
STREAM_KEYS = ("zed_left", "zed_right", "zed_depth", "zed_imu", "thermal_left", "thermal_right")
#: the thermal FFC status topics
STATUS_KEYS = ("thermal_left_status", "thermal_right_status")
#: the sensor_msgs/CameraInfo topics (the calibration a bag carries)
INFO_KEYS = ("zed_left_info", "zed_right_info", "thermal_left_info", "thermal_right_info")
KEYS = STREAM_KEYS + STATUS_KEYS + INFO_KEYS
IMAGE_KEYS = ("zed_left", "zed_right", "thermal_left", "thermal_right")

#: the released TartanRGBT stack's topics (its topic_list.yaml; upstream-tartanrgbt.md)
TARTANRGBT = {
    "zed_left": "/zed/zed_node/left_raw/image_raw_color",
    "zed_right": "/zed/zed_node/right_raw/image_raw_color",
    "zed_imu": "/zed/zed_node/imu/data",
    "thermal_left": "/thermal_left/image",
    "thermal_right": "/thermal_right/image",
    "thermal_left_status": "/thermal_left/ffc_status",
    "thermal_right_status": "/thermal_right/ffc_status",
    "zed_left_info": "/zed/zed_node/left_raw/camera_info",
    "zed_right_info": "/zed/zed_node/right_raw/camera_info",
    "thermal_left_info": "/thermal_left/camera_info",
    "thermal_right_info": "/thermal_right/camera_info",
}
#: what records depth for each layout when it has none (for the refusal of an export that needs it)
NO_DEPTH_HINT = ("record the ZED depth (on_device.zed_depth_mode), name a depth topic (zed_depth) in a "
                 "--topics map, or compute it from the stereo pair (--depth stereo, the default without one)")


class LayoutError(Exception):
    """A topic map or a recording whose layout cannot be used; one line."""


@dataclass(frozen=True)
class Layout:
    name: str                    # "project", "tartanrgbt" or the topic map's path
    topics: dict                 # key of KEYS -> topic (only the keys the layout has)

    def get(self, key: str) -> str | None:
        return self.topics.get(key)


def project(rig) -> Layout:
    t = rig.desc.on_device.topics
    return Layout("project", {k: getattr(t, k) for k in STREAM_KEYS + STATUS_KEYS})


def tartanrgbt() -> Layout:
    return Layout("tartanrgbt", dict(TARTANRGBT))


def load_topic_map(path: Path) -> Layout:
    """The layout of a ``--topics`` YAML file: ``KEY: /topic`` lines, keys among :data:`KEYS`; thermal_left,
    thermal_right and zed_left are required."""
    path = Path(path)
    try:
        data = yaml.safe_load(path.read_text())
    except OSError as exc:
        raise LayoutError(f"{path}: cannot read the topic map ({exc.strerror or exc})") from None
    except yaml.YAMLError as exc:
        raise LayoutError(f"{path}: not YAML ({str(exc).splitlines()[0]})") from None
    if not isinstance(data, dict):
        raise LayoutError(f"{path}: a topic map is a mapping of stream names to topics ({', '.join(KEYS)})")
    unknown = [str(k) for k in data if k not in KEYS]
    if unknown:
        raise LayoutError(f"{path}: unknown stream name {unknown[0]!r} (expected: {', '.join(KEYS)})")
    bad = [k for k, v in data.items() if not (isinstance(v, str) and v.startswith("/"))]
    if bad:
        raise LayoutError(f"{path}: {bad[0]}: {data[bad[0]]!r} is not a topic name (expected /...)")
    missing = [k for k in ("zed_left", "thermal_left", "thermal_right") if k not in data]
    if missing:
        raise LayoutError(f"{path}: no {', '.join(missing)} topic: the topic map needs zed_left, thermal_left "
                          f"and thermal_right")
    return Layout(str(path), dict(data))


def _listing(topics, n: int = 12) -> str:
    topics = sorted(topics)
    more = f" ... ({len(topics) - n} more)" if len(topics) > n else ""
    return (", ".join(topics[:n]) + more) if topics else "none"


def detect(bag: Path, found: set[str], rig, topic_map: Layout | None = None) -> Layout:
    """The layout of a recording holding the topics ``found``; raises :class:`LayoutError` (one line naming
    ``bag`` and the topics found) when it is none of the known ones, or when the topic map's image topics
    are not there."""
    if topic_map is not None:
        absent = [topic_map.topics[k] for k in IMAGE_KEYS if k in topic_map.topics
                  and topic_map.topics[k] not in found]
        if absent:
            raise LayoutError(f"{bag}: the topic map {topic_map.name} names {', '.join(absent)}, not in the "
                              f"recording (topics found: {_listing(found)})")
        return topic_map
    candidates = [project(rig), tartanrgbt()]
    score = [sum(lay.topics.get(k) in found for k in IMAGE_KEYS) for lay in candidates]
    best = max(range(len(candidates)), key=lambda i: (score[i], -i))
    if score[best] == 0:
        expected = "; ".join(f"{lay.name}: {', '.join(lay.topics[k] for k in IMAGE_KEYS)}" for lay in candidates)
        raise LayoutError(f"{bag}: unknown topic layout: topics found: {_listing(found)}; expected the image "
                          f"topics of a known layout ({expected}), or give a topic map with --topics FILE")
    return candidates[best]
