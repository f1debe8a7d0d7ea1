"""The index's chunk scan in parts (platform_tools.dataset.indexscan): however the chunks are split among the export's
pool workers, the parts merge back into mcap's own order (checked against mcap's reader on a file with chunks that
overlap in time and tie), and the recording's index is the same as one scan's, on a simulated recording, on one
without its status topic (FFC state from telemetry) and on one written by rosbags; a damaged chunk met in a worker
is one line naming the file."""
from __future__ import annotations

import io
import json
import shutil

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap.writer import CompressionType

from platform_tools.dataset import engines, indexscan, mcapscan
from platform_tools.dataset.recording import RecordingError, open_recording
from tests.dataset import rosbags_rig
from tests.dataset.test_dataset_speed_scan import _mcap_file
from tests.dataset.test_dataset_telemetry import without_status


def _raw(topics) -> indexscan.Wanted:
    return indexscan.Wanted(streams={}, others=frozenset(topics), stamps_only=frozenset(), telemetry_rows=0,
                            model_px=(640, 512))


@pytest.mark.parametrize("n", [1, 2, 3, 7, 1000])
def test_parts_merge_back_into_mcaps_order(tmp_path, n):
    f = tmp_path / "a.mcap"
    f.write_bytes(_mcap_file(CompressionType.ZSTD))      # zstd chunks that overlap in time, ties
    with open(f, "rb") as fh:
        reader = make_reader(fh)
        summary = reader.get_summary()
        want = [(c.topic, m.log_time, m.data) for _, c, m in
                reader.iter_messages(topics=["/t0", "/t2"], log_time_order=True)]
    channels = {cid: c.topic for cid, c in summary.channels.items() if c.topic != "/t1"}
    chunks = [c for c in summary.chunk_indexes if channels.keys() & set(c.message_index_offsets)]
    runs = indexscan.parts(chunks, n)
    assert len(runs) == min(n, len(chunks)) and sum(runs, []) == sorted(chunks, key=lambda c: c.chunk_start_offset)
    import heapq
    merged = list(heapq.merge(*[indexscan.scan_part(str(f), channels, _raw(["/t0", "/t2"]), r) for r in runs]))
    assert [(e[3], e[0], e[4]) for e in merged] == want and len(want) == 400
    assert [t for _, t, _ in want] != sorted(t for _, t, _ in want)[::-1]


def test_parts_are_of_about_equal_size_but_the_last_four():
    class C:
        def __init__(self, off, size):
            self.chunk_start_offset, self.uncompressed_size = off, size
    rng = np.random.default_rng(1)
    chunks = [C(i, int(s)) for i, s in enumerate(rng.integers(1000, 3000, 400))]
    runs = indexscan.parts(list(reversed(chunks)), 8)
    sizes = [sum(c.uncompressed_size for c in r) for r in runs]
    weights = [1, 1, 1, 1, *indexscan.TAIL_WEIGHTS]
    unit = sum(sizes) / sum(weights)
    assert len(runs) == 8 and all(abs(s - w * unit) <= 2 * 3000 for s, w in zip(sizes, weights))
    assert [c.chunk_start_offset for r in runs for c in r] == list(range(400))


def _same(a, b) -> None:
    assert a.streams.keys() == b.streams.keys()
    for s, st in a.streams.items():
        other = b.streams[s]
        for field in ("stamp_ns", "log_ns", "file_index", "frozen", "counter"):
            x, y = getattr(st, field), getattr(other, field)
            assert (x is None) == (y is None), (s, field)
            if x is not None:
                np.testing.assert_array_equal(x, y, err_msg=f"{s}.{field}")
    assert a.status == b.status and a.status_source == b.status_source
    assert a.camera_info == b.camera_info and a.status_lag_frames == b.status_lag_frames
    assert a.clock_step_values == b.clock_step_values


@pytest.fixture(scope="module")
def pool():
    p = engines.Pool(2)
    yield p
    p.close()


@pytest.fixture(scope="module")
def recordings(sim, rig, tmp_path_factory):
    root = tmp_path_factory.mktemp("indexscan")
    without_status(sim[0], root / "nostatus", rig)
    rosbags_rig.write(root / "rosbags", rosbags_rig.Spec(telemetry=True, camera_info=True, steps=((60, 20.0, "zed"),)),
                      rosbags_rig.project_layout(rig))
    return {"sim": sim[0], "nostatus": root / "nostatus", "rosbags": root / "rosbags"}


@pytest.mark.parametrize("name", ["sim", "nostatus", "rosbags"])
@pytest.mark.parametrize("per_worker", [indexscan.PARTS_PER_WORKER, 1000])
def test_the_index_is_the_same_scanned_in_parts(recordings, name, per_worker, rig, pool, monkeypatch):
    monkeypatch.setattr(indexscan, "PARTS_PER_WORKER", per_worker)
    one = open_recording(recordings[name], rig)
    split = open_recording(recordings[name], rig, pool=pool)
    _same(one, split)
    thermal = one.streams["thermal_left"]
    assert len(thermal.stamp_ns) > 50 and thermal.frozen.any()      # non-trivial: frozen frames were found
    if name != "sim":
        assert one.status_source["thermal_left"] == ("telemetry" if name == "nostatus" else "status")


def test_a_damaged_chunk_met_in_a_worker_is_one_line(sim, rig, pool, tmp_path):
    dst = tmp_path / "rec"
    shutil.copytree(sim[0], dst)
    bag = next((dst / "bag").glob("*.mcap"))
    data = bytearray(bag.read_bytes())
    summary = make_reader(io.BytesIO(bytes(data))).get_summary()
    c = summary.chunk_indexes[len(summary.chunk_indexes) // 2]
    end = c.chunk_start_offset + c.chunk_length
    data[end - 400:end - 8] = bytes(392)
    bag.write_bytes(bytes(data))
    with pytest.raises(RecordingError) as exc:
        open_recording(dst, rig, pool=pool)
    msg = str(exc.value)
    assert str(bag) in msg and "damaged MCAP" in msg and "\n" not in msg
    _same(open_recording(sim[0], rig, pool=pool), open_recording(sim[0], rig))    # the pool still works


@pytest.mark.parametrize("workers", [False, True])
def test_a_status_message_cut_short_is_one_line(sim, rig, pool, tmp_path, workers):
    """The FFC status messages are decoded where the chunks are scanned (ffcstatus.read, in the workers): one cut
    short there is the same one line naming the file as here."""
    from mcap.writer import Writer
    dst = tmp_path / "rec"
    shutil.copytree(sim[0], dst)
    bag = next((dst / "bag").glob("*.mcap"))
    out = io.BytesIO()
    w = Writer(out, compression=CompressionType.ZSTD)
    w.start()
    schemas, channels, seen = {}, {}, 0
    for schema, channel, msg in make_reader(io.BytesIO(bag.read_bytes())).iter_messages(log_time_order=False):
        if schema.id not in schemas:
            schemas[schema.id] = w.register_schema(schema.name, schema.encoding, schema.data)
        if channel.id not in channels:
            channels[channel.id] = w.register_channel(channel.topic, channel.message_encoding, schemas[schema.id],
                                                      channel.metadata)
        data = msg.data
        if channel.topic == "/thermal/right/status":
            seen += 1
            data = data[:14] if seen == 40 else data
        w.add_message(channels[channel.id], log_time=msg.log_time, publish_time=msg.publish_time,
                      sequence=msg.sequence, data=data)
    w.finish()
    assert seen > 40
    bag.write_bytes(out.getvalue())
    with pytest.raises(RecordingError) as exc:
        open_recording(dst, rig, pool=pool if workers else None)
    msg = str(exc.value)
    assert str(bag) in msg and "damaged MCAP" in msg and "\n" not in msg


def test_sync_check_with_workers_reports_what_one_process_does(platform_tools, recordings):
    runs = [platform_tools("sync-check", str(recordings["rosbags"]), "--json", "--workers", n) for n in ("1", "2")]
    # the recording's 5 missing trigger pulses (of 150) fail the 2 % drop limit: exit 1 from both, nothing else fails
    assert [r.returncode for r in runs] == [1, 1], runs[1].stderr
    one, two = (json.loads(r.stdout) for r in runs)
    assert one == two and one["triggers"] and one["verdict"] == "fail"
    assert {c["check"].split()[-1] for c in one["checks"] if not c["ok"]} == {"drops"}
    bad = platform_tools("sync-check", str(recordings["rosbags"]), "--workers", "0")
    assert bad.returncode == 2 and "--workers 0" in bad.stderr and bad.stdout == ""


@pytest.mark.parametrize("workers", ["1", "2"])
def test_the_index_shows_its_progress_on_a_terminal(sim, workers):
    """stderr a terminal (a pseudo-terminal of 120 columns here): a bar named after the file, counting its chunks
    (tqdm draws it at the start and redraws it at most every 0.1 s, so only the first state is sure to be seen);
    stdout the report alone."""
    import fcntl
    import os
    import pty
    import struct
    import subprocess
    import sys
    import termios

    from tests.conftest import REPO
    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 40, 120, 0, 0))
    r = subprocess.run([sys.executable, "-m", "platform_tools.cli.main", "sync-check", str(sim[0]), "--json",
                        "--workers", workers, "--set", "processing.sync_limits.max_drop_percent=6"],
                       cwd=REPO, stdout=subprocess.PIPE, stderr=slave, text=True, timeout=300)
    os.close(slave)
    seen = b""
    while True:
        try:
            got = os.read(master, 65536)
        except OSError:                     # EIO: the terminal's other side is closed and drained
            break
        if not got:
            break
        seen += got
    os.close(master)
    assert r.returncode == 0 and json.loads(r.stdout)["verdict"] == "pass"
    text = seen.decode(errors="replace")
    bag = next((sim[0] / "bag").glob("*.mcap"))
    n = len(make_reader(open(bag, "rb")).get_summary().chunk_indexes)
    assert f"index {bag.name}:" in text and f"0/{n} [" in text and "chunk" in text


@pytest.mark.parametrize("how", ["map", "run"])
def test_a_worker_that_dies_is_one_line_and_the_others_are_stopped(how):
    """A worker killed under the pool (here it exits at once, as one killed by the out-of-memory killer would
    vanish): one line naming what happened and what to do, not concurrent.futures' BrokenProcessPool traceback."""
    import os
    p = engines.Pool(2)
    with pytest.raises(engines.EngineError) as exc:
        if how == "map":
            p.map(os._exit, [(3,), (3,)])
        else:
            p.run(os._exit, [3, 3], lambda t, r: None)
    assert "a worker process died" in str(exc.value) and "--workers" in str(exc.value) and "\n" not in str(exc.value)
    import multiprocessing
    assert [c for c in multiprocessing.active_children() if c not in p._before] == []     # every worker reaped


def _fields_by_whole_bytes(data, wanted: indexscan.Wanted) -> tuple:
    """thermal_fields as it was written for a frame's whole bytes (before the frames were read in part): the reference
    the part-read path is checked against."""
    import hashlib

    from platform_tools.boson.telemetry import TelemetryError, decode_image_data
    from platform_tools.dataset.cdr import image_layout
    try:
        height, width, step, off = image_layout(data)
    except (ValueError, IndexError, __import__("struct").error):
        return hashlib.blake2b(data[-indexscan.TAIL_BYTES:], digest_size=16).digest(), -1, -1
    rows = indexscan.rows_below(wanted.telemetry_rows, wanted.model_px, width, height)
    end = off + (height - rows) * step
    counter = ffc = -1
    if rows:
        try:
            tel = decode_image_data(memoryview(data)[off:off + height * step], height, step, rows)
            counter, ffc = int(tel.frame_counter), int(tel.ffc_status)
        except TelemetryError:
            pass
    return hashlib.blake2b(data[max(off, end - indexscan.TAIL_BYTES):end], digest_size=16).digest(), counter, ffc


#: frame sizes as (divisor of the camera's width and height, telemetry rows below or not); None: a 7 x 3 frame
FRAMES = {"full, telemetry": (1, True), "full": (1, False), "half, telemetry": (2, True),
          "sixteenth, telemetry": (16, True), "tiny": None}


@pytest.mark.parametrize("frame", sorted(FRAMES))
@pytest.mark.parametrize("frame_id", ["", "thermal_left_optical", "x" * 300])
def test_a_thermal_frame_read_in_part_gives_what_its_whole_bytes_give(frame, frame_id, rig):
    """Frames serialised by rosbags (the rig's camera size with and without its telemetry rows, half and a sixteenth
    of it, whose tail is the whole image, and a tiny one; a frame_id longer than the fields read first), whole and cut
    short: the digest, frame counter and FFC state read through a Sparse (fields, then one read of the tail and
    telemetry rows) are those of the whole bytes."""
    from rosbags.typesys import Stores, get_typestore

    from platform_tools.dataset.recording import _thermal_px
    ts = get_typestore(Stores.ROS2_HUMBLE)
    rows, (cam_w, cam_h) = rig.desc.on_device.thermal_telemetry_rows, _thermal_px(rig)
    telemetry = FRAMES[frame] is not None and FRAMES[frame][1]
    w, h = (7, 3) if FRAMES[frame] is None else (cam_w // FRAMES[frame][0], cam_h // FRAMES[frame][0])
    rng = np.random.default_rng(w * h + len(frame_id))
    px = rng.integers(0, 65535, (h + rows * telemetry, w), dtype=np.uint16)
    if telemetry:                    # Boson telemetry rows at the bottom, as the rig's cameras send them
        line = rosbags_rig.telemetry_line(123456, 2, 99, rows * w * 2)
        px[-rows:] = np.frombuffer(line, "<u2").reshape(rows, w)
    raw = bytes(ts.serialize_cdr(rosbags_rig._image(ts, 1_700_000_000_123_456_789, frame_id, px, "mono16"),
                                 "sensor_msgs/msg/Image"))
    wanted = indexscan.Wanted(streams={"/t": "thermal_left"}, others=frozenset(), stamps_only=frozenset(),
                              telemetry_rows=rows, model_px=(cam_w, cam_h))
    for data in (raw, raw[:max(60, len(raw) - 1000)], raw[:40]):
        want = _fields_by_whole_bytes(data, wanted)
        part = mcapscan.Sparse(data[:indexscan.FIELDS_BYTES], len(data), io.BytesIO(data), 0, "test")
        assert indexscan.thermal_fields(part, wanted, {}) == want
        assert indexscan.thermal_fields(memoryview(data), wanted, {}) == want
        assert indexscan.event(5, 0, 0, "/t", part, wanted, {}) == (5, 0, 0, "/t", 1_700_000_000_123_456_789) + want
    if telemetry:
        assert _fields_by_whole_bytes(raw, wanted)[1:] == (123456, 2)       # non-trivial: the telemetry was read


def test_a_rosbags_recording_read_in_part_indexes_as_through_mcaps_reader(recordings, rig, pool, monkeypatch):
    """rosbags writes its chunks uncompressed: the index reads them in part (stamps, thermal fields, tails, telemetry;
    the status messages whole), one process or in the pool, and gets what mcap's reader gives it reading every
    message whole (the scan switched off)."""
    from platform_tools.dataset import recording
    calls = []
    real_sparse = mcapscan._sparse_messages

    def spy(*a, **k):
        got = real_sparse(*a, **k)
        calls.append(got is not None)
        return got
    monkeypatch.setattr(mcapscan, "_sparse_messages", spy)
    one = open_recording(recordings["rosbags"], rig)
    assert calls and all(calls)                      # every chunk of this recording was read in part
    split = open_recording(recordings["rosbags"], rig, pool=pool)    # the workers fork with the spy: not counted
    monkeypatch.setattr(mcapscan, "has_chunk_index", lambda summary: False)
    recording._summaries.clear()
    ref = open_recording(recordings["rosbags"], rig)
    _same(one, ref)
    _same(split, ref)
    left = ref.streams["thermal_left"]
    assert left.frozen.any() and (left.counter >= 0).all() and ref.status        # telemetry and status read


@pytest.mark.parametrize("zstd", [False, True])
def test_a_recording_copied_by_rosbags_indexes_as_the_original(sim, rig, pool, tmp_path, zstd):
    """bench/rosbags_copy.py (the export bench's second source): the simulated recording written again by rosbags'
    writer, in its own chunks, uncompressed (read in part) or zstd (read whole): the same index, one process and in
    the pool; the copy refuses to overwrite, in one line, exit 2."""
    from tests.conftest import bench_module
    copier = bench_module("rosbags_copy")
    out = tmp_path / "copy"
    assert copier.copy(sim[0], out, zstd=zstd) > 500
    from mcap.reader import make_reader
    (f,) = (out / "bag").glob("*.mcap")
    with open(f, "rb") as fh:
        compressions = {c.compression for c in make_reader(fh).get_summary().chunk_indexes}
    assert compressions == ({"zstd"} if zstd else {""})
    ref = open_recording(sim[0], rig)
    _same(open_recording(out, rig), ref)
    _same(open_recording(out, rig, pool=pool), ref)
    assert (out / "truth.json").read_bytes() == (sim[0] / "truth.json").read_bytes()
    before = f.read_bytes()
    assert copier.main([str(sim[0]), str(out)]) == 2 and f.read_bytes() == before
