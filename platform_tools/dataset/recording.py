"""Open a recording and index its streams by header stamp, without decoding images.

A recording is given as a rosbag2 folder (``metadata.yaml`` + MCAP files), a folder holding one
(``simulate-rig`` writes ``DIR/bag``), or MCAP files. The index holds, per rig stream, each message's
header stamp (read straight from the CDR bytes: encapsulation header, then ``int32 sec``,
``uint32 nanosec``), its log time (to find it again) and, for thermal images, whether its pixels
repeat the previous frame's (a frozen frame: FFC). The thermal status topic is decoded (it is small;
:mod:`.ffcstatus`), and so are the ``sensor_msgs/CameraInfo`` topics (the calibration a bag may carry). Which
topics those are comes from the recording's layout (:mod:`.layout`: this rig's, the released TartanRGBT
stack's, or a ``--topics`` map), detected from the topics the bag holds; every other topic is ignored.
When a thermal camera has no status messages, its FFC state comes from the Boson telemetry rows of
its frames instead (``platform_tools.boson.telemetry``; a frozen frame is then judged on the image rows
only: the telemetry keeps changing during an FFC).

Bad input ends in :class:`RecordingError` with one line: a truncated MCAP (no index: the recorder
was killed), a damaged one, a recording without a stream the caller needs.
"""
from __future__ import annotations

import hashlib
import logging
import struct
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml

from .cdr import STAMP_BYTES, compressed_fields, header_stamp, image_fields, image_layout  # noqa: F401 - re-exported

log = logging.getLogger(__name__)

#: rig streams by their short name -> attribute of rig.desc.on_device.topics
STREAMS = ("zed_left", "zed_right", "zed_depth", "zed_imu", "thermal_left", "thermal_right")
#: the two Bosons' streams
THERMAL = ("thermal_left", "thermal_right")
CAMERAS = ("zed_left", "zed_right") + THERMAL
STATUS = ("thermal_left_status", "thermal_right_status")
RECOVERED_SUFFIX = ".recovered.mcap"
#: the first bytes of an SQLite 3 database (rosbag2's sqlite3 storage, ``.db3`` files)
SQLITE_MAGIC = b"SQLite format 3\x00"
SQLITE_SUFFIX = ".db3"


class RecordingError(Exception):
    """A recording that cannot be used as given; ``str()`` is one line naming the file."""


@dataclass
class Stream:
    name: str
    topic: str
    stamp_ns: np.ndarray             # int64, in recording order
    log_ns: np.ndarray               # int64
    file_index: np.ndarray           # int16: which MCAP file
    frozen: np.ndarray | None = None  # thermal: same pixels as the previous frame
    #: thermal: the Boson telemetry frame counter of each frame (int64), None without telemetry rows
    counter: np.ndarray | None = None


@dataclass
class Recording:
    name: str
    path: Path
    files: list[Path]
    streams: dict[str, Stream]
    #: thermal camera -> list of (host stamp ns, ffc_status int): from the status topic, else from
    #: the telemetry rows of each frame (see status_source)
    status: dict[str, list[tuple[int, int]]] = field(default_factory=dict)
    #: thermal camera -> "status" (the status topic), "telemetry" (the frames' telemetry rows) or None
    status_source: dict[str, str | None] = field(default_factory=dict)
    recovered: list[str] = field(default_factory=list)
    #: thermal camera -> triggers its status rows were moved later to lie on the FFC freeze (ffcstatus.frame_lag)
    status_lag_frames: dict[str, int] = field(default_factory=dict)
    #: the topic layout (layout.Layout.name): "project", "tartanrgbt" or a topic map's path
    layout: str = "project"
    #: camera (zed_left, zed_right, thermal_left, thermal_right) -> its latest sensor_msgs/CameraInfo, as
    #: {"topic", "width", "height", "distortion_model", "d", "k", "p"} (lists of floats)
    camera_info: dict = field(default_factory=dict)
    #: thermal camera -> {frame stamp ns: clock_step_ns} of its DiagnosticArray status (the device node's host
    #: clock steps, sync.device_clock_steps), read by the index's one pass; None: not read (sync reads them)
    clock_step_values: dict | None = None

    def has(self, name: str) -> bool:
        return name in self.streams and len(self.streams[name].stamp_ns) > 0

    def require(self, *names: str, why: str) -> None:
        missing = [n for n in names if not self.has(n)]
        if missing:
            topics = ", ".join(sorted({self.streams[n].topic for n in missing if n in self.streams}
                                      | {self._topics.get(n, f"no {n} topic in the {self.layout} layout")
                                         for n in missing}))
            raise RecordingError(f"{self.path}: no {' / '.join(missing)} messages ({topics}); {why}")

    _topics: dict = field(default_factory=dict)

    def identity(self) -> dict:
        """What identifies the recording's content (for an export's fingerprint): files, sizes, counts."""
        h = hashlib.sha256()
        for f in self.files:
            st = f.stat()
            h.update(f"{f.name}:{st.st_size}".encode())
        return {"name": self.name, "path": str(self.path),
                "files": [f.name for f in self.files],
                "messages": {n: int(len(s.stamp_ns)) for n, s in self.streams.items()},
                "fingerprint": h.hexdigest()[:16]}


def sqlite_refusal(path: Path, bag: Path) -> RecordingError:
    """The one line for a sqlite3 rosbag2 bag: what it is and how to convert it (this package reads MCAP)."""
    return RecordingError(
        f"{path}: a sqlite3 rosbag2 bag (.db3), not MCAP; this tool reads MCAP: convert it first with "
        f"`rosbags-convert --src {bag} --dst {bag.with_name(bag.name + '-mcap')} --dst-storage mcap` "
        f"(or `ros2 bag convert`)")


def _is_sqlite(path: Path) -> bool:
    try:
        with open(path, "rb") as f:
            return f.read(len(SQLITE_MAGIC)) == SQLITE_MAGIC
    except OSError:
        return False


def mcap_files(path: Path) -> tuple[str, list[Path]]:
    """(recording name, its MCAP files in order) for a folder or a file; a sqlite3 bag is refused."""
    path = Path(path)
    if not path.exists():
        raise RecordingError(f"{path}: no such file or folder")
    if path.is_file():
        if path.suffix == SQLITE_SUFFIX or _is_sqlite(path):
            raise sqlite_refusal(path, path.parent)
        if path.suffix != ".mcap":
            raise RecordingError(f"{path}: not an MCAP file (expected .mcap or a rosbag2 folder)")
        return path.stem, [path]
    meta = path / "metadata.yaml"
    if meta.is_file():
        try:
            info = yaml.safe_load(meta.read_text())["rosbag2_bagfile_information"]
            files = [path / p for p in info["relative_file_paths"]]
        except (yaml.YAMLError, KeyError, TypeError) as exc:
            raise RecordingError(f"{meta}: not a rosbag2 metadata file ({exc})") from None
        if info.get("storage_identifier") == "sqlite3" or any(f.suffix == SQLITE_SUFFIX for f in files):
            raise sqlite_refusal(path, path)
        name = path.parent.name if path.name == "bag" else path.name
        missing = [f for f in files if not f.is_file()]
        if missing:
            raise RecordingError(f"{missing[0]}: listed in {meta.name} but missing")
        return name, files
    if (path / "bag").is_dir():
        return path.name, mcap_files(path / "bag")[1]
    files = sorted(p for p in path.glob("*.mcap") if not p.name.endswith(RECOVERED_SUFFIX))
    if not files and any(path.glob("*" + SQLITE_SUFFIX)):
        raise sqlite_refusal(path, path)
    if not files:
        raise RecordingError(f"{path}: no MCAP files (expected a rosbag2 folder or .mcap files)")
    return path.name, files


#: MCAP summaries read in this process, by (path, size, modification time): the summary (chunk index, channels,
#: schemas; 0.2 s of CPU for a 12 s full-size recording) is read once per file version, not by every reader of it
#: (the truncation check, the channels, the index, the size probe, each chunk of a worker)
_summaries: dict[tuple[str, int, int], object] = {}
#: how many files' summaries a process keeps
SUMMARIES_KEPT = 8


def mcap_reader(fh, path):
    """An ``mcap`` SeekingReader of the open file ``fh`` (the file at ``path``) with its summary read once per
    process and file version. Errors are the reader's (McapError, EOFError, struct.error, ValueError)."""
    import os

    from mcap.reader import SeekingReader
    st = os.stat(path)
    key = (os.path.realpath(path), st.st_size, st.st_mtime_ns)     # one entry however the path is spelt
    reader = SeekingReader(fh)
    if key in _summaries:
        reader._summary = _summaries[key]       # the reader's own cache (mcap.reader.SeekingReader.get_summary)
        return reader
    summary = reader.get_summary()
    if summary is not None:                     # a truncated file has none: read again, it may be recovered
        while len(_summaries) >= SUMMARIES_KEPT:
            _summaries.pop(next(iter(_summaries)))
        _summaries[key] = summary
    return reader


def read_summaries(path: Path) -> None:
    """The summaries of a recording's MCAP files read into this process's cache (:func:`mcap_reader`): the export
    reads them before forking its pool's workers, which then inherit them instead of each parsing them again at its
    first chunk (0.06 to 0.2 s each for a 60 s full-size recording, docs/dataset.md "Speed"). Quiet: a file it cannot
    read is left for :func:`open_recording` to report."""
    try:
        _, files = mcap_files(path)
        for f in files:
            with open(f, "rb") as fh:
                mcap_reader(fh, f)
    except Exception:           # noqa: BLE001 - see the docstring: open_recording says what is wrong, in one line
        pass


def _is_truncated(path: Path) -> bool:
    from mcap.exceptions import McapError
    try:
        with open(path, "rb") as f:
            return mcap_reader(f, path).get_summary() is None
    except (McapError, EOFError, struct.error, ValueError):
        return True


def resolve_files(files: list[Path], recover: bool) -> tuple[list[Path], list[str]]:
    """Replace each truncated MCAP by its recovered copy: an existing ``.recovered.mcap`` beside it,
    or one written now with ``recover=True`` (the original is never modified)."""
    out, notes = [], []
    for f in files:
        if _is_sqlite(f):
            raise sqlite_refusal(f, f.parent)
        if not _is_truncated(f):
            out.append(f)
            continue
        copy = f.with_name(f.name[:-len(".mcap")] + RECOVERED_SUFFIX)
        if copy.is_file() and not _is_truncated(copy):
            out.append(copy)
            notes.append(f"{f.name}: truncated; using its recovered copy {copy.name}")
            continue
        if not recover:
            raise RecordingError(
                f"{f}: truncated MCAP (no index: the recorder was killed or lost power); run again with "
                f"--recover to salvage its readable messages into {copy.name} (the original is kept)")
        from firmware.device.mcapcheck import recover as mcap_recover
        rec = mcap_recover(f)
        out.append(Path(rec.path))
        notes.append(f"{f.name}: truncated; recovered {rec.messages} messages into {copy.name}"
                     + (f" (stopped at: {rec.stopped_at})" if rec.stopped_at else ""))
    for n in notes:
        log.warning(n)
    return out, notes


def telemetry_rows(rig, width: int, height: int) -> int:
    """How many Boson telemetry rows (platform_tools.boson.telemetry) a thermal frame of ``width`` x
    ``height`` px carries below its image (0: none)."""
    from .indexscan import rows_below
    return rows_below(rig.desc.on_device.thermal_telemetry_rows, _thermal_px(rig), width, height)


def _thermal_px(rig) -> tuple[int, int]:
    """(width, height) in px of the rig's thermal camera model."""
    model = rig.camera_model(rig.desc.sensors.thermal.camera_model)
    return model.width_px, model.height_px


def _channels(files: list[Path]) -> dict[str, tuple[str, Path]]:
    """topic -> (schema name, first file holding it), from the MCAP summaries."""
    from mcap.exceptions import McapError
    out: dict[str, tuple[str, Path]] = {}
    for f in files:
        try:
            with open(f, "rb") as fh:
                summary = mcap_reader(fh, f).get_summary()
        except (McapError, EOFError, struct.error, ValueError) as exc:
            raise RecordingError(f"{f}: damaged MCAP ({type(exc).__name__}: {exc}); "
                                 f"run again with --recover to salvage what is readable") from None
        if summary is None:
            continue
        for ch in summary.channels.values():
            sc = summary.schemas.get(ch.schema_id)
            out.setdefault(ch.topic, (sc.name if sc else "", f))
    return out


def _info(m, topic: str) -> dict:
    return {"topic": topic, "width": int(m.width), "height": int(m.height),
            "distortion_model": str(m.distortion_model), "d": [float(x) for x in m.d],
            "k": [float(x) for x in m.k], "p": [float(x) for x in m.p]}


def open_recording(path: Path, rig, *, recover: bool = False, streams=STREAMS, topic_map=None,
                   pool=None) -> Recording:
    """Index a recording's rig streams (and the thermal FFC status, and its camera_info); ``topic_map``: a
    :class:`.layout.Layout` from ``--topics`` (default: detected); ``pool``: an :class:`.engines.Pool` whose workers
    scan the files' chunks side by side (:mod:`.indexscan`), else they are scanned here."""
    from mcap.exceptions import McapError
    from mcap_ros2.decoder import DecoderFactory

    from . import ffcstatus, indexscan, mcapscan
    from .layout import INFO_KEYS, LayoutError, detect

    name, files = mcap_files(path)
    files, notes = resolve_files(files, recover)
    channels = _channels(files)
    try:
        lay = detect(Path(path), set(channels), rig, topic_map)
    except LayoutError as exc:
        raise RecordingError(str(exc)) from None
    topics = lay.topics
    by_topic = {topics[s]: s for s in streams if s in topics}
    status_topics = {topics[s]: s.removesuffix("_status") for s in STATUS if s in topics}
    info_topics = {topics[k]: k.removesuffix("_info") for k in INFO_KEYS if k in topics}
    status_types = {}
    for topic in status_topics:
        if topic in channels:
            schema_name, f = channels[topic]
            try:
                status_types[topic] = ffcstatus.check_type(schema_name)
            except ffcstatus.StatusTypeError as exc:
                raise RecordingError(f"{f}: {topic}: {exc}") from None
    for topic in info_topics:
        if topic in channels and ffcstatus.normalise(channels[topic][0]) != "sensor_msgs/msg/CameraInfo":
            raise RecordingError(f"{channels[topic][1]}: {topic}: camera_info of type {channels[topic][0]}; "
                                 f"expected sensor_msgs/msg/CameraInfo")
    cols: dict[str, list] = {s: [] for s in by_topic.values()}
    digests: dict[str, bytes] = {}
    status: dict[str, list[tuple[int, int]]] = {c: [] for c in status_topics.values()}
    from_telemetry: dict[str, list[tuple[int, int]]] = {c: [] for c in THERMAL}
    infos: dict[str, dict] = {}
    clock_steps: dict[str, dict[int, int]] = {c: {} for c in status_topics.values()}
    last_stamp: dict[str, int] = {}
    decoder = DecoderFactory()
    last_info: dict[str, tuple[int, bytes]] = {}      # camera_info topic -> (file, data) of its latest message
    wanted = indexscan.Wanted(
        streams={t: s for t, s in by_topic.items() if t in channels},
        others=frozenset(t for t in list(status_topics) + list(info_topics) if t in channels),
        # the streams of which the index needs only the header stamp (of a thermal frame: its tail and telemetry too)
        stamps_only=frozenset(t for t, s in by_topic.items() if not s.startswith("thermal")),
        telemetry_rows=rig.desc.on_device.thermal_telemetry_rows, model_px=_thermal_px(rig),
        status={t: ty for t, ty in status_types.items() if t in channels})
    for fi, f in enumerate(files):
        try:
            with open(f, "rb") as fh:
                reader = mcap_reader(fh, f)
                summary = reader.get_summary()
                if mcapscan.has_chunk_index(summary):
                    events = indexscan.scan_file(f, summary, wanted, pool)
                    schemas = {c.topic: summary.schemas.get(c.schema_id) for c in summary.channels.values()}
                else:
                    events, schemas = indexscan.scan_reader(reader, wanted)
            for ev in events:
                log_time, topic = ev[0], ev[3]
                s = by_topic.get(topic)
                if s is not None:
                    _, _, _, _, stamp, digest, counter, ffc = ev
                    frozen = False
                    if digest is not None:            # a thermal frame
                        frozen = digests.get(s) == digest
                        digests[s] = digest
                        last_stamp[s] = stamp
                        if ffc >= 0:
                            from_telemetry[s].append((stamp, ffc))
                    cols[s].append((stamp, log_time, fi, frozen, counter))
                    continue
                if topic in info_topics:          # the last one is kept: decoded once, below
                    last_info[topic] = (fi, ev[4])
                    continue
                cam = status_topics[topic]
                status[cam] += ffcstatus.rows_of(ev[4], log_time, last_stamp.get(cam))
                clock_steps[cam].update(ev[4].clock_steps)
            for topic, (fj, data) in last_info.items():
                if fj != fi:
                    continue
                dec = decoder.decoder_for("cdr", schemas[topic])
                infos[info_topics[topic]] = _info(dec(data), topic)
        except (McapError, EOFError, struct.error, ValueError) as exc:
            raise RecordingError(f"{f}: damaged MCAP ({type(exc).__name__}: {exc}); "
                                 f"run again with --recover to salvage what is readable") from None
    source = {}
    for cam in from_telemetry:
        if status.get(cam):
            source[cam] = "status"
        elif from_telemetry[cam]:
            status[cam], source[cam] = from_telemetry[cam], "telemetry"
        else:
            status[cam], source[cam] = [], None
    out, lag = {}, {}
    for s, rows in cols.items():
        a = np.array(rows, dtype=np.int64).reshape(-1, 5)
        thermal = s.startswith("thermal")
        out[s] = Stream(s, topics[s], a[:, 0], a[:, 1], a[:, 2].astype(np.int16),
                        a[:, 3].astype(bool) if thermal else None,
                        a[:, 4] if thermal and len(a) and (a[:, 4] >= 0).all() else None)
    for cam in from_telemetry:     # the FFC freeze in the frames says which frame each status row belongs to
        if cam in out and status[cam]:
            st = out[cam]
            k = ffcstatus.trigger_index(st.stamp_ns, st.counter, 1e9 / rig.desc.sync.rate_hz)
            lag[cam] = ffcstatus.frame_lag(status[cam], st.stamp_ns, st.frozen, k)
            status[cam] = ffcstatus.shifted(status[cam], st.stamp_ns, lag[cam], k)
    rec = Recording(name, Path(path), files, out, status, status_source=source, recovered=notes,
                    layout=lay.name, camera_info=infos, status_lag_frames=lag,
                    clock_step_values={c: v for c, v in clock_steps.items() if v})
    rec._topics = dict(topics)          # every topic of the layout (streams, status, camera_info)
    return rec
