"""The export's ZED images (processing.zed_images, ``--zed-images``): a compressed topic's JPEG written as the recording
holds it, byte for byte, in ``zed_left/NNNNNN.jpg`` (index column ``zed_left_jpg``); a raw topic, or ``png``, as PNG
(``zed_left_png``). The recordings are written by the rosbags library (tests/dataset/rosbags_rig.py) and read back here
by rosbags' reader, not by this project's MCAP code."""
from __future__ import annotations

import csv
import subprocess
import sys

import cv2
import numpy as np
import pytest
from rosbags.highlevel import AnyReader

from platform_tools.dataset.chunk import THERMAL_KINDS
from platform_tools.dataset.export import Params, export
from tests.conftest import REPO
from tests.dataset import rosbags_rig

pytestmark = pytest.mark.slow          # two bags written with rosbags, four exports


@pytest.fixture(scope="module")
def bags(tmp_path_factory, rig):
    """{"jpeg": a recording whose ZED topics are CompressedImage JPEGs, "raw": one with raw bgra8 Images}."""
    out = {}
    for kind in ("jpeg", "raw"):
        bag = tmp_path_factory.mktemp(kind) / "bag"
        rosbags_rig.write(bag, rosbags_rig.Spec(triggers=40, missing=(), drop=0.0, ffc={}, seed=8,
                                                zed_compressed=kind == "jpeg"), rosbags_rig.project_layout(rig))
        out[kind] = bag
    return out


def recorded(bag, topic: str) -> dict[int, object]:
    """Header stamp (ns) -> the message of ``topic``, as rosbags reads and deserialises it."""
    out = {}
    with AnyReader([bag]) as reader:
        for conn, _, raw in reader.messages(connections=[c for c in reader.connections if c.topic == topic]):
            m = reader.deserialize(raw, conn.msgtype)
            out[m.header.stamp.sec * 10**9 + m.header.stamp.nanosec] = m
    return out


def rows(out) -> list[dict]:
    with open(out / "index.csv") as f:
        return list(csv.DictReader(f))


@pytest.fixture(scope="module")
def exported(bags, rig, tmp_path_factory):
    """(folder, index rows) of the JPEG bag exported as recorded (the default) and with zed_images png, and of the raw
    bag exported by default."""
    base = tmp_path_factory.mktemp("zedout")
    out = {}
    for name, bag, how in (("jpeg", bags["jpeg"], "rig"), ("jpeg-png", bags["jpeg"], "png"),
                           ("raw", bags["raw"], "rig")):
        export([bag], base / name, rig, Params.from_rig(rig, rate_hz=10, zed_images=how), engine="inline")
        out[name] = base / name, rows(base / name)
    return out


def test_the_default_is_as_recorded_and_the_rig_key_takes_what_the_writer_knows(rig):
    import typing

    from platform_tools.dataset.chunk import ZED_IMAGES
    from platform_tools.rig.schema import Processing
    assert rig.desc.processing.zed_images == "as_recorded"
    assert Params.from_rig(rig).zed_images == "as_recorded"
    hint = typing.get_type_hints(Processing)["zed_images"]
    assert typing.get_args(hint) == ZED_IMAGES


def test_a_compressed_zed_image_is_the_recorded_jpeg_byte_for_byte(exported, bags, rig):
    out, index = exported["jpeg"]
    assert len(index) >= 8
    topics = rosbags_rig.project_layout(rig)
    for side in ("zed_left", "zed_right"):
        msgs = recorded(bags["jpeg"], topics[side])
        for r in index:
            assert f"{side}_png" not in r and r[f"{side}_jpg"].endswith(f"{side}/{int(r['sample']):06d}.jpg")
            assert (out / r[f"{side}_jpg"]).read_bytes() == bytes(msgs[int(r[f"t_{side}_ns"])].data)


def test_png_writes_the_pixels_the_jpeg_decodes_to_and_the_thermal_files_do_not_change(exported, bags, rig):
    (out, index), (out_j, index_j) = exported["jpeg-png"], exported["jpeg"]
    msgs = recorded(bags["jpeg"], rosbags_rig.project_layout(rig)["zed_left"])
    assert [r["t_zed_left_ns"] for r in index] == [r["t_zed_left_ns"] for r in index_j]
    for r, rj in zip(index, index_j):
        assert "zed_left_jpg" not in r and r["zed_left_png"].endswith(".png")
        jpeg = np.frombuffer(bytes(msgs[int(r["t_zed_left_ns"])].data), np.uint8)
        assert np.array_equal(cv2.imread(str(out / r["zed_left_png"]), cv2.IMREAD_UNCHANGED),
                              cv2.imdecode(jpeg, cv2.IMREAD_COLOR))
        for cam in ("thermal_left", "thermal_right"):       # the registration saw the same pixels
            for kind in THERMAL_KINDS:
                col = f"{cam}_{kind}_png"
                assert (out / r[col]).read_bytes() == (out_j / rj[col]).read_bytes(), col


def test_a_raw_zed_topic_is_written_as_png(exported, bags, rig):
    out, index = exported["raw"]
    msgs = recorded(bags["raw"], rosbags_rig.project_layout(rig)["zed_right"])
    for r in index:
        assert "zed_right_jpg" not in r and r["zed_right_png"].endswith(".png")
        m = msgs[int(r["t_zed_right_ns"])]
        bgra = np.asarray(m.data, np.uint8).reshape(m.height, m.width, 4)
        assert np.array_equal(cv2.imread(str(out / r["zed_right_png"]), cv2.IMREAD_UNCHANGED), bgra[..., :3])


def test_a_removed_jpeg_is_written_again_on_resume(bags, rig, tmp_path):
    out = tmp_path / "ds"
    params = Params.from_rig(rig, rate_hz=10, chunk_size=4)
    export([bags["jpeg"]], out, rig, params, engine="inline")
    first = rows(out)[5]
    path = out / first["zed_left_jpg"]
    data = path.read_bytes()
    path.unlink()
    again = export([bags["jpeg"]], out, rig, params, engine="inline")
    assert again["resumed"] and again["chunks_run"] == 1 and path.read_bytes() == data


def test_the_command_takes_zed_images_and_the_rig_key_is_checked(bags, tmp_path):
    def run(*extra):
        return subprocess.run([sys.executable, "-m", "platform_tools.cli.main", "export", str(bags["jpeg"]),
                               "--out", str(tmp_path / "ds"), "--rate", "5", "--workers", "1", "-q", *extra],
                              cwd=REPO, capture_output=True, text=True, timeout=300)
    r = run("--set", "processing.zed_images=gif")
    assert r.returncode == 2 and "processing.zed_images" in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "ds").exists()
    r = run("--zed-images", "png")
    assert r.returncode == 0, r.stderr
    index = rows(tmp_path / "ds")
    assert index and all(x["zed_left_png"] and "zed_left_jpg" not in x for x in index)
    card = (tmp_path / "ds" / "README.md").read_text()
    assert "--zed-images png" in card and "- ZED images: decoded and written as PNG." in card
