"""`calibrate thermal --bag REC --topic T` on a recording written by the rosbags library (an independent
ROS 2 bag writer, not this project's simulator or recorder): board views rendered by calibrate synth,
some only as motion-blurred frames, an FFC span (frozen frames, and the status topic true for two
more frames after the freeze), topic names as the released TartanRGBT stack spells them."""
from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

from calibration.cli import main

T0_NS = 1_700_000_000 * 1_000_000_000
PERIOD_NS = 33_333_333
TOPIC, STATUS = "/thermal_left/image", "/thermal_left/ffc_status"
BLURRED_VIEWS = (2, 6, 7, 19, 20, 22)   # none within the 0.1 s FFC margin
FFC_AFTER_VIEW = 11          # the Boson freezes on this view's frame ...
FFC_FROZEN = 8               # ... for this many frames
FFC_SETTLING_VIEWS = (12, 13)  # the status stays true over these views' frames


def _write_bag(path, frames):
    """frames: list of (uint16 image, in_ffc bool); one per trigger, 30 Hz."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore
    ts = get_typestore(Stores.ROS2_HUMBLE)
    T = ts.types
    with Writer(path, version=8, storage_plugin=StoragePlugin.MCAP) as w:
        ci = w.add_connection(TOPIC, "sensor_msgs/msg/Image", typestore=ts)
        cs = w.add_connection(STATUS, "std_msgs/msg/Bool", typestore=ts)
        for k, (img, ffc) in enumerate(frames):
            stamp = T0_NS + k * PERIOD_NS
            hdr = T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](sec=stamp // 10**9,
                                                                                  nanosec=stamp % 10**9),
                                           frame_id="thermal_left_optical")
            msg = T["sensor_msgs/msg/Image"](header=hdr, height=img.shape[0], width=img.shape[1], encoding="mono16",
                                             is_bigendian=0, step=img.shape[1] * 2,
                                             data=np.frombuffer(img.astype("<u2").tobytes(), np.uint8))
            w.write(ci, stamp + 6_000_000, ts.serialize_cdr(msg, "sensor_msgs/msg/Image"))
            w.write(cs, stamp + 7_000_000, ts.serialize_cdr(T["std_msgs/msg/Bool"](data=bool(ffc)), "std_msgs/msg/Bool"))


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    from calibration.synth import render_dataset
    src = tmp_path_factory.mktemp("views") / "set"
    truth = render_dataset(src, n=24, difficulty="real", board=(10, 7), square=0.04, seed=12, show_progress=False)
    frames, kinds, view_of = [], [], []
    for v, im in enumerate(truth["images"]):
        img = cv2.imread(str(src / im["file"]), cv2.IMREAD_UNCHANGED)
        if v in BLURRED_VIEWS:                    # a fast move: a 9 px smear along x
            frames.append((cv2.blur(img, (9, 1)), False))
            kinds.append("blurred")
        else:
            frames.append((img, v in FFC_SETTLING_VIEWS))
            kinds.append("ffc" if v in FFC_SETTLING_VIEWS else "sharp")
        view_of.append(v)
        if v == FFC_AFTER_VIEW:
            for _ in range(FFC_FROZEN):
                frames.append((img.copy(), True))
                kinds.append("ffc")
                view_of.append(v)
    bag = tmp_path_factory.mktemp("rec") / "bag"
    _write_bag(bag, frames)
    stamps = [T0_NS + k * PERIOD_NS for k in range(len(frames))]
    return bag, truth, dict(zip(stamps, kinds)), dict(zip(stamps, view_of))


@pytest.mark.slow
def test_topic_without_bag_and_bag_without_topic(tmp_path, capsys):
    for argv in (["--images", str(tmp_path), "--topic", TOPIC], ["--bag", str(tmp_path)]):
        code = main(["thermal", *argv, "--board", "10x7", "--square", "0.04", "--out", str(tmp_path / "o")])
        err = capsys.readouterr().err
        assert code == 2 and "--topic" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()


@pytest.mark.slow
def test_bag_frames_are_chosen_sharp_outside_ffc_and_covering(recording, tmp_path, capsys):
    bag, truth, kind_of, view_of = recording
    out = tmp_path / "cal"
    code = main(["thermal", "--bag", str(bag), "--topic", TOPIC, "--board", "10x7", "--square", "0.04",
                 "--out", str(out), "--max-frames", "14", "--json", "-q", "--exit-zero"])
    stdout, err = capsys.readouterr()
    assert code == 0, err
    summary = json.loads(stdout)
    chosen = json.loads((out / "frames.json").read_text())
    stamps = chosen["chosen_stamps_ns"]
    assert 8 <= len(stamps) <= 14
    kinds = [kind_of[s] for s in stamps]
    assert kinds.count("blurred") == 0, kinds
    assert kinds.count("ffc") == 0, kinds
    assert chosen["ffc_spans"] and chosen["ffc_or_frozen"] >= FFC_FROZEN + len(FFC_SETTLING_VIEWS)
    # blurred frames: refused by their board's sharpness, or no board found in them at all
    assert chosen["blurred"] >= 1
    assert chosen["blurred"] + chosen["looked_at"] - chosen["with_board"] >= len(BLURRED_VIEWS)
    assert len({view_of[s] for s in stamps}) == len(stamps)          # no view twice
    # coverage: every ninth of the image that the usable views' true corners reach, the chosen reach too
    W, H = truth["imagersize"]

    def ninths(views):
        out_ = set()
        for v in views:
            q = np.array([c for c in truth["images"][v]["corners"] if c is not None])
            out_ |= {(int(3 * x / W), int(3 * y / H)) for x, y in q}
        return out_
    usable = {view_of[s] for s, k in kind_of.items() if k == "sharp"}
    assert ninths({view_of[s] for s in stamps}) == ninths(usable)
    assert summary["n_images_used"] >= 8 and summary["frames"]["looked_at"] >= 14
    assert {p.name for p in out.iterdir()} >= {"thermal.cameramodel", "frames.json", "corners.vnl"}


@pytest.mark.slow
def test_missing_bag_and_a_topic_without_thermal_images(tmp_path, capsys):
    """One line each, exit 2, nothing written: a recording that is not there; a topic the recording
    has no thermal images on (the line names the ones it has)."""
    bag = tmp_path / "tiny"
    rng = np.random.default_rng(0)
    _write_bag(bag, [((7500 + rng.normal(0, 20, (32, 40))).astype(np.uint16), False) for _ in range(3)])
    for argv, expect in ((["--bag", str(tmp_path / "none"), "--topic", TOPIC], "no such file"),
                         (["--bag", str(bag), "--topic", "/thermal_right/image"], TOPIC)):
        code = main(["thermal", *argv, "--board", "10x7", "--square", "0.04", "--out", str(tmp_path / "o")])
        err = capsys.readouterr().err
        assert code == 2 and expect in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "o").exists()
