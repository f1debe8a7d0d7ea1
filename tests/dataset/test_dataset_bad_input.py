"""Bad input: one clear line each (exit 2), nothing lost, nothing half-written."""
from __future__ import annotations

import hashlib

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap.writer import Writer


def filtered(src_dir, dst_dir, drop_topics):
    """A copy of the recording's MCAP without some topics (as a recorder that lacked them would write)."""
    dst_dir.mkdir(parents=True)
    with open(src_dir / "bag" / "bag_0.mcap", "rb") as f, open(dst_dir / "bag_0.mcap", "wb") as o:
        reader = make_reader(f)
        summary = reader.get_summary()
        w = Writer(o)
        w.start(profile="ros2", library="test")
        schemas = {sid: w.register_schema(s.name, s.encoding, s.data) for sid, s in summary.schemas.items()}
        chans = {cid: w.register_channel(c.topic, c.message_encoding, schemas[c.schema_id])
                 for cid, c in summary.channels.items() if c.topic not in drop_topics}
        for _, channel, msg in reader.iter_messages():
            if channel.id in chans:
                w.add_message(chans[channel.id], msg.log_time, msg.data, msg.publish_time, msg.sequence)
        w.finish()
    return dst_dir


def sha(p):
    return hashlib.sha256(p.read_bytes()).hexdigest()


@pytest.mark.slow
def test_truncated_mcap_is_named_and_recovered_on_request(platform_tools, sim, tmp_path):
    rec = tmp_path / "cut"
    rec.mkdir()
    data = (sim[0] / "bag" / "bag_0.mcap").read_bytes()
    (rec / "bag_0.mcap").write_bytes(data[: int(len(data) * 0.6)])     # power loss mid-recording
    before = sha(rec / "bag_0.mcap")
    r = platform_tools("sync-check", str(rec))
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1
    assert "truncated MCAP" in r.stderr and "--recover" in r.stderr
    r = platform_tools("export", str(rec), "--out", str(tmp_path / "ds"))
    assert r.returncode == 2 and "truncated" in r.stderr and not (tmp_path / "ds").exists()
    r = platform_tools("sync-check", str(rec), "--recover", "--json",
                       "--set", "processing.sync_limits.max_drop_percent=6")
    assert r.returncode == 0, r.stderr
    assert sha(rec / "bag_0.mcap") == before                             # the original is kept as it was
    assert (rec / "bag_0.recovered.mcap").is_file()
    # the recovered copy is used from then on, without --recover
    r = platform_tools("export", str(rec), "--out", str(tmp_path / "ds"))
    assert r.returncode == 0, r.stderr


@pytest.mark.slow
@pytest.mark.parametrize("drop, words", [
    (("thermal_left", "thermal_right"), ["no thermal_left", "/thermal/left/image_raw"]),
    (("zed_depth",), ["no zed_depth", "needs the ZED depth"])])
def test_recording_without_a_stream(platform_tools, sim, rig, tmp_path, drop, words):
    topics = {getattr(rig.desc.on_device.topics, d) for d in drop}
    rec = filtered(sim[0], tmp_path / "rec", topics)
    # without depth the default computes it from the stereo pair: asking for the recorded depth is refused
    extra = ["--depth", "recorded"] if "zed_depth" in drop else []
    r = platform_tools("export", str(rec), "--out", str(tmp_path / "ds"), *extra)
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert all(w in r.stderr for w in words), r.stderr
    assert not (tmp_path / "ds").exists()
    r = platform_tools("sync-check", str(rec), "--set", "processing.sync_limits.max_drop_percent=6")
    if "zed_depth" in drop:
        assert r.returncode == 0, r.stderr            # sync needs no depth
    else:
        assert r.returncode == 2 and "no thermal_left" in r.stderr


@pytest.mark.slow
def test_calibration_of_other_cameras_is_refused(platform_tools, calibrate, sim, tmp_path):
    import mrcal
    cal = tmp_path / "cal"
    assert calibrate("nominal", "--out", str(cal)).returncode == 0
    m = mrcal.cameramodel(str(cal / "thermal_left.cameramodel"))
    lens, k = m.intrinsics()
    other = mrcal.cameramodel(intrinsics=(lens, k), imagersize=np.array([640, 480]),   # a 640x480 camera
                              extrinsics_rt_fromref=m.extrinsics_rt_fromref())
    other.write(str(cal / "thermal_left.cameramodel"))
    r = platform_tools("export", str(sim[0]), "--out", str(tmp_path / "ds"), "--calibration", str(cal))
    assert r.returncode == 2 and "is for 640x480 images" in r.stderr and "not these cameras" in r.stderr
    assert not (tmp_path / "ds").exists()
    (cal / "thermal_right.cameramodel").unlink()
    r = platform_tools("export", str(sim[0]), "--out", str(tmp_path / "ds"), "--calibration", str(cal))
    assert r.returncode == 2 and "thermal_right.cameramodel: missing" in r.stderr


@pytest.mark.slow
def test_a_calibrated_set_is_used_and_recorded(platform_tools, calibrate, sim, tmp_path):
    cal = tmp_path / "cal"
    assert calibrate("nominal", "--out", str(cal)).returncode == 0
    r = platform_tools("export", str(sim[0]), "--out", str(tmp_path / "ds"), "--calibration", str(cal), "--json")
    assert r.returncode == 0, r.stderr
    assert '"source": "' + str(cal) in r.stdout
    header = (tmp_path / "ds" / "index.csv").read_text().splitlines()[1]
    assert str(cal) in header


@pytest.mark.slow
def test_output_folder_holding_a_different_export(platform_tools, sim, tmp_path):
    out = tmp_path / "ds"
    assert platform_tools("export", str(sim[0]), "--out", str(out)).returncode == 0
    index = (out / "index.csv").read_text()
    r = platform_tools("export", str(sim[0]), "--out", str(out), "--ffc-margin", "0")
    assert r.returncode == 2 and "holds a different export" in r.stderr and "ffc_margin 3" in r.stderr
    assert (out / "index.csv").read_text() == index
    lost = sorted((out / "rec" / "thermal_left" / "8bit").glob("*.png"))[0]
    lost.unlink()                                   # an image lost since: its chunk is redone
    r = platform_tools("export", str(sim[0]), "--out", str(out), "--json")
    assert r.returncode == 0 and '"chunks_run": 1' in r.stdout and lost.is_file()
    assert (out / "index.csv").read_text() == index
