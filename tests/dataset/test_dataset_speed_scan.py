"""Reading MCAP chunks straight (platform_tools.dataset.mcapscan) and decoding images from their CDR bytes
(decode.decode_cdr), checked against other libraries: files written by mcap's own Writer (zstd, lz4, none; chunks
overlapping in time, equal log times) read by mcap's reader; messages serialised by rosbags' typestore compared
with the arrays they were made from; a rosbags-written recording indexed and decoded as mcap's reader would."""
from __future__ import annotations

import io

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer
from rosbags.typesys import Stores, get_typestore

from platform_tools.dataset import decode, mcapscan, recording
from platform_tools.dataset.recording import RecordingError, mcap_files, open_recording
from tests.dataset import rosbags_rig


def _mcap_file(compression, seed=0) -> bytes:
    """Three channels, 600 messages with log times jumping back and forth (chunks overlap in time) and repeated (ties
    broken by file position), small chunks: what mcap's log-time order has to sort out."""
    rng = np.random.default_rng(seed)
    buf = io.BytesIO()
    w = Writer(buf, chunk_size=2000, compression=compression)
    w.start()
    sid = w.register_schema("s", "raw", b"")
    chans = [w.register_channel(f"/t{i}", "raw", sid) for i in range(3)]
    for n in range(600):
        log = int(rng.integers(0, 50)) * 1000 + (n // 100) * 20_000
        w.add_message(chans[n % 3], log_time=log, publish_time=log, sequence=n,
                      data=rng.integers(0, 255, int(rng.integers(1, 300)), dtype=np.uint8).tobytes())
    w.finish()
    return buf.getvalue()


@pytest.mark.parametrize("compression", [CompressionType.ZSTD, CompressionType.LZ4, CompressionType.NONE])
@pytest.mark.parametrize("ordered", [True, False])
def test_the_scan_yields_what_mcaps_reader_yields(compression, ordered):
    data = _mcap_file(compression)
    reader = make_reader(io.BytesIO(data))
    summary = reader.get_summary()
    assert len(summary.chunk_indexes) > 5
    ids = {cid: c.topic for cid, c in summary.channels.items() if c.topic != "/t1"}
    want = [(c.topic, m.log_time, m.data) for _, c, m in
            reader.iter_messages(topics=sorted(ids.values()), log_time_order=ordered)]
    got = [(ids[cid], t, bytes(d)) for cid, t, d in
           mcapscan.iter_messages(io.BytesIO(data), summary, set(ids), log_time_order=ordered)]
    assert got == want and len(got) == 400
    if ordered:
        assert [t for _, t, _ in got] == sorted(t for _, t, _ in got)
        assert got != sorted(got, key=lambda m: m[1])[::-1]          # non-trivial: ties and overlaps exist


def test_a_damaged_chunk_is_one_line():
    data = bytearray(_mcap_file(CompressionType.ZSTD))
    summary = make_reader(io.BytesIO(bytes(data))).get_summary()
    c = summary.chunk_indexes[2]
    data[c.chunk_start_offset + c.chunk_length - 40:c.chunk_start_offset + c.chunk_length - 8] = bytes(32)
    with pytest.raises(mcapscan.ScanError, match=f"chunk at offset {c.chunk_start_offset}") as exc:
        list(mcapscan.iter_messages(io.BytesIO(bytes(data)), summary, set(summary.channels)))
    assert "\n" not in str(exc.value)


TS = get_typestore(Stores.ROS2_HUMBLE)


def _header():
    return TS.types["std_msgs/msg/Header"](stamp=TS.types["builtin_interfaces/msg/Time"](sec=5, nanosec=7),
                                           frame_id="a_frame_id_of_odd_length")


@pytest.mark.parametrize("encoding,dtype,ch,pad,big", [
    ("mono16", np.uint16, 1, 0, False), ("16UC1", np.uint16, 1, 6, True), ("32FC1", np.float32, 1, 4, False),
    ("mono8", np.uint8, 1, 3, False), ("bgr8", np.uint8, 3, 0, False), ("rgb8", np.uint8, 3, 5, False),
    ("bgra8", np.uint8, 4, 0, False)])
def test_a_raw_image_decodes_to_the_array_it_was_made_from(encoding, dtype, ch, pad, big):
    """sensor_msgs/Image serialised by rosbags, rows padded (step beyond the pixels), either byte order."""
    rng = np.random.default_rng(3)
    h, w = 7, 11
    arr = (rng.random((h, w, ch)) * 1000 if dtype == np.float32 else
           rng.integers(0, np.iinfo(dtype).max, (h, w, ch))).astype(dtype)
    if dtype == np.float32:
        arr[0, 0] = np.nan
    px = arr.astype(np.dtype(dtype).newbyteorder(">" if big else "<")).tobytes()
    row = w * ch * np.dtype(dtype).itemsize
    body = b"".join(px[r * row:(r + 1) * row] + bytes(range(pad)) for r in range(h))
    msg = TS.types["sensor_msgs/msg/Image"](header=_header(), height=h, width=w, encoding=encoding,
                                            is_bigendian=int(big), step=row + pad,
                                            data=np.frombuffer(body, np.uint8))
    cdr = TS.serialize_cdr(msg, "sensor_msgs/msg/Image")
    expect = arr[..., 0] if ch == 1 else (arr[..., ::-1] if encoding == "rgb8" else arr[..., :3])
    for data in (bytes(cdr), memoryview(bytes(cdr))):
        got = decode.decode_cdr("sensor_msgs/msg/Image", data)
        assert got.dtype == np.dtype(dtype) and got.dtype.isnative and got.flags.writeable
        np.testing.assert_array_equal(got, expect)
    back = TS.deserialize_cdr(cdr, "sensor_msgs/msg/Image")
    np.testing.assert_array_equal(decode.decode_image("sensor_msgs/msg/Image", back), expect)


@pytest.mark.parametrize("fmt", ["png", "jpeg"])
def test_a_compressed_image_decodes_as_opencv_decodes_its_bytes(fmt):
    import cv2
    img = np.random.default_rng(4).integers(0, 255, (9, 13, 3), dtype=np.uint8)
    enc = cv2.imencode("." + ("jpg" if fmt == "jpeg" else fmt), img)[1].reshape(-1)
    msg = TS.types["sensor_msgs/msg/CompressedImage"](header=_header(), format=fmt, data=enc)
    cdr = bytes(TS.serialize_cdr(msg, "sensor_msgs/msg/CompressedImage"))
    got = decode.decode_cdr("sensor_msgs/msg/CompressedImage", memoryview(cdr))
    np.testing.assert_array_equal(got, cv2.imdecode(enc, cv2.IMREAD_UNCHANGED))
    if fmt == "png":
        np.testing.assert_array_equal(got, img)


def test_a_short_message_is_refused():
    msg = TS.types["sensor_msgs/msg/Image"](header=_header(), height=4, width=4, encoding="mono8", is_bigendian=0,
                                            step=4, data=np.zeros(16, np.uint8))
    cdr = bytes(TS.serialize_cdr(msg, "sensor_msgs/msg/Image"))
    with pytest.raises(ValueError, match="holds"):
        decode.decode_cdr("sensor_msgs/msg/Image", cdr[:-3])


@pytest.fixture(scope="module")
def bag(tmp_path_factory, rig):
    bag = tmp_path_factory.mktemp("scan") / "bag"
    rosbags_rig.write(bag, rosbags_rig.Spec(triggers=40, ffc={}), rosbags_rig.project_layout(rig))
    return bag


@pytest.mark.slow
def test_a_rosbags_recording_indexes_and_decodes_as_through_mcaps_reader(bag, rig):
    """The index (stamps, log times, frozen flags, counters, status) equals one built by mcap's reader (the scan
    switched off), and every image decoded from the chunks equals mcap_ros2's."""
    (f,) = mcap_files(bag)[1]
    rec = open_recording(bag, rig)
    real = mcapscan.has_chunk_index
    try:
        mcapscan.has_chunk_index = lambda summary: False
        ref = open_recording(bag, rig)
    finally:
        mcapscan.has_chunk_index = real
    assert set(rec.streams) == set(ref.streams)
    for s, st in rec.streams.items():
        r = ref.streams[s]
        for field in ("stamp_ns", "log_ns", "file_index", "frozen", "counter"):
            a, b = getattr(st, field), getattr(r, field)
            assert (a is None and b is None) or np.array_equal(a, b), (s, field)
    assert rec.status == ref.status and rec.camera_info == ref.camera_info
    wanted, logs = {}, []
    for s in decode.IMAGE_STREAMS:
        if rec.has(s):
            st = rec.streams[s]
            for i in range(0, len(st.stamp_ns), 7):
                wanted[(st.topic, int(st.stamp_ns[i]))] = (s, i)
                logs.append(int(st.log_ns[i]))
    got = {k: img for k, _, img in decode.iter_frames([str(f)], wanted, logs)}
    with open(f, "rb") as fh:
        ref_imgs = {k: img for k, _, img in decode._iter_frames_mcap(
            recording.mcap_reader(fh, f), str(f), sorted({t for t, _ in wanted}), wanted, logs)}
    assert len(got) == len(wanted) == len(ref_imgs)
    for k in wanted.values():
        np.testing.assert_array_equal(got[k], ref_imgs[k])
    # the ZED images kept as their recorded files (export's zed_images as_recorded): the same through both paths
    keep = frozenset(rec.streams[s].topic for s in ("zed_left", "zed_right"))
    enc = {k: e for k, _, e in decode.iter_frames([str(f)], wanted, logs, keep_encoded=keep)}
    with open(f, "rb") as fh:
        ref_enc = {k: e for k, _, e in decode._iter_frames_mcap(
            recording.mcap_reader(fh, f), str(f), sorted({t for t, _ in wanted}), wanted, logs, keep)}
    assert set(enc) == set(ref_enc) == set(wanted.values())
    zed = [k for k in wanted.values() if k[0] in ("zed_left", "zed_right")]
    assert zed and all(isinstance(enc[k], decode.Encoded) and enc[k].suffix == ".jpg" for k in zed)
    for k in wanted.values():
        if k in zed:
            assert enc[k] == ref_enc[k]
            np.testing.assert_array_equal(enc[k].image(), got[k])
        else:
            np.testing.assert_array_equal(enc[k], got[k])


@pytest.mark.slow
@pytest.mark.parametrize("stream", ["thermal_left", "zed_left"])
def test_a_damaged_recording_is_one_line(bag, rig, tmp_path, stream):
    """A message record's length damaged in an uncompressed chunk (rosbags writes them so): the index reads that
    record in part, from its message index, and says the file is damaged, in one line. A thermal frame (read as a
    Sparse: fields, tail, telemetry) and a ZED image (read for its stamp only)."""
    import shutil
    copy = tmp_path / "bag"
    shutil.copytree(bag, copy)
    (f,) = mcap_files(copy)[1]
    with open(f, "rb") as fh:
        summary = make_reader(fh).get_summary()
        topic = open_recording(bag, rig).streams[stream].topic
        cid = next(i for i, c in summary.channels.items() if c.topic == topic)
        chunks = [c for c in summary.chunk_indexes if cid in c.message_index_offsets]
        c = chunks[len(chunks) // 2]
        assert c.compression == ""              # rosbags writes its chunks uncompressed
        offset = mcapscan.message_index(fh, c, [cid])[0][0]
    raw = bytearray(f.read_bytes())
    record = c.chunk_start_offset + 9 + 28 + 4 + 8 + offset   # Chunk header: record head, times, size, crc, "", length
    assert raw[record] == mcapscan.OP_MESSAGE
    raw[record + 1:record + 9] = (2 ** 40).to_bytes(8, "little")
    f.write_bytes(bytes(raw))
    recording._summaries.clear()
    with pytest.raises(RecordingError, match="damaged MCAP") as exc:
        open_recording(copy, rig)
    assert str(f) in str(exc.value) and f"chunk at offset {c.chunk_start_offset}" in str(exc.value)
    assert "\n" not in str(exc.value)


def _big_and_small_file(seed=1, compression=CompressionType.ZSTD) -> bytes:
    """Chunks of one large compressible message (a depth map's kind) followed by small ones: what the index needs only
    the header of, and what it needs whole."""
    rng = np.random.default_rng(seed)
    buf = io.BytesIO()
    w = Writer(buf, chunk_size=400_000, compression=compression)
    w.start()
    sid = w.register_schema("s", "raw", b"")
    big, small = w.register_channel("/big", "raw", sid), w.register_channel("/small", "raw", sid)
    for n in range(40):
        log = n * 1000
        w.add_message(big, log_time=log, publish_time=log, sequence=n,
                      data=rng.integers(0, 255, 16, dtype=np.uint8).tobytes() + bytes(500_000))
        w.add_message(small, log_time=log + 1, publish_time=log + 1, sequence=n,
                      data=rng.integers(0, 255, int(rng.integers(1, 300)), dtype=np.uint8).tobytes())
    w.finish()
    return buf.getvalue()


@pytest.mark.parametrize("ordered", [True, False])
def test_heads_cut_the_data_and_the_decompression_not_the_order(ordered):
    data = _big_and_small_file()
    summary = make_reader(io.BytesIO(data)).get_summary()
    ids = {cid: c.topic for cid, c in summary.channels.items()}
    big = next(cid for cid, t in ids.items() if t == "/big")
    want = [(ids[c.id], m.log_time, m.data[:12] if c.id == big else m.data) for _, c, m in
            make_reader(io.BytesIO(data)).iter_messages(log_time_order=ordered)]
    full, cut = {}, {}
    assert [(ids[c], t, bytes(d)[:12] if c == big else bytes(d)) for c, t, d in
            mcapscan.iter_messages(io.BytesIO(data), summary, set(ids), log_time_order=ordered, stats=full)] == want
    got = [(ids[c], t, bytes(d)) for c, t, d in
           mcapscan.iter_messages(io.BytesIO(data), summary, set(ids), log_time_order=ordered, heads={big: 12},
                                  stats=cut)]
    assert got == want and len(got) == 80
    assert cut["decompressed_bytes"] < full["decompressed_bytes"] / 10


@pytest.mark.parametrize("ordered", [True, False])
@pytest.mark.parametrize("on_disk", [True, False])
def test_an_uncompressed_chunk_is_read_in_part_and_in_mcaps_order(ordered, on_disk, tmp_path):
    """Uncompressed chunks (mcap's writer, no compression): a channel in ``heads`` gives its first bytes, one in
    ``sparse`` a Sparse whose every range is the message's (read from the file, os.pread, or from a stream), the
    others their whole data; in mcap's order, reading a tenth of what a whole read does."""
    data = _big_and_small_file(compression=CompressionType.NONE)
    summary = make_reader(io.BytesIO(data)).get_summary()
    assert {c.compression for c in summary.chunk_indexes} == {""} and len(summary.chunk_indexes) > 10
    ids = {cid: c.topic for cid, c in summary.channels.items()}
    big = next(cid for cid, t in ids.items() if t == "/big")
    want = [(ids[c.id], m.log_time, m.data) for _, c, m in
            make_reader(io.BytesIO(data)).iter_messages(log_time_order=ordered)]
    f = tmp_path / "u.mcap"
    f.write_bytes(data)
    rng = np.random.default_rng(2)
    for mode in ("heads", "sparse"):
        stats = {}
        with (open(f, "rb") if on_disk else io.BytesIO(data)) as fh:
            got = []
            for c, t, d in mcapscan.iter_messages(fh, summary, set(ids), log_time_order=ordered, stats=stats,
                                                  **{mode: {big: 12}}):
                if isinstance(d, mcapscan.Sparse):
                    assert mode == "sparse" and c == big
                    whole = want[len(got)][2]
                    assert len(d) == len(whole) and d.head == whole[:12]
                    for a, b in [(0, 5), (0, len(whole)), (len(whole) - 9, len(whole))] + [
                            tuple(sorted(rng.integers(0, len(whole) + 1, 2))) for _ in range(3)]:
                        assert d.read(int(a), int(b)) == whole[a:b]
                    with pytest.raises(mcapscan.ScanError, match="bytes 0:"):
                        d.read(0, len(whole) + 1)
                    d = whole
                else:
                    assert c != big or mode == "heads"
                    d = bytes(d)
                got.append((ids[c], t, d[:12] if (c == big and mode == "heads") else d))
        assert got == [(t, log, d[:12] if (t == "/big" and mode == "heads") else d) for t, log, d in want]
        assert len(got) == 80 and 0 < stats["read_bytes"] + stats.get("decompressed_bytes", 0) < len(data) / 10


@pytest.mark.parametrize("compression", [CompressionType.ZSTD, CompressionType.NONE])
def test_a_message_index_that_points_elsewhere_is_one_line(compression):
    data = bytearray(_big_and_small_file(compression=compression))
    summary = make_reader(io.BytesIO(bytes(data))).get_summary()
    ids = {cid: c.topic for cid, c in summary.channels.items()}
    big = next(cid for cid, t in ids.items() if t == "/big")
    c = summary.chunk_indexes[1]
    pos = c.message_index_offsets[big] + 9 + 6 + 8      # the offset of its first (log_time, offset) pair
    data[pos:pos + 8] = (7).to_bytes(8, "little")
    with pytest.raises(mcapscan.ScanError, match=f"chunk at offset {c.chunk_start_offset}"):
        list(mcapscan.iter_messages(io.BytesIO(bytes(data)), summary, set(ids), heads={big: 12}))
