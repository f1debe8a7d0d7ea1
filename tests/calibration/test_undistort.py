"""`calibrate undistort`: rectified pinhole views of images rendered through truth lenses of other
families (Kannala-Brandt read from an OpenCV fisheye YAML, stereographic from a .cameramodel)."""
from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

from calibration.cli import main
from calibration.detect import detect_corners

BOARD = (10, 7)


def worst_line_px(corners: np.ndarray, W: int, H: int) -> float:
    """The largest distance of a corner from the straight line fitted to its board row or column."""
    g = corners.reshape(H, W, 2)
    worst = 0.0
    for line in list(g) + list(g.transpose(1, 0, 2)):
        line = line[np.isfinite(line[:, 0])]
        if len(line) >= 3:
            m = line.mean(0)
            n = np.linalg.svd(line - m)[2][1]
            worst = max(worst, float(np.abs((line - m) @ n).max()))
    return worst


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    """3 'easy' images through each foreign truth lens, with its model file as `calibrate` writes them."""
    from calibration.formats.conversions import Representation
    from calibration.formats.opencv_yaml import opencv_yaml
    from calibration.synth import render_dataset
    from calibration.synth.truth_families import truth_lens
    out = {}
    for family in ("kannala-brandt", "stereographic"):
        folder = tmp_path_factory.mktemp(family) / "set"
        render_dataset(folder, n=3, difficulty="easy", board=BOARD, seed=2, lens=truth_lens(family),
                       show_progress=False)
        if family == "kannala-brandt":
            fs = cv2.FileStorage(str(folder / "truth_fisheye.yaml"), cv2.FILE_STORAGE_READ)
            K, D = fs.getNode("camera_matrix").mat(), fs.getNode("distortion_coefficients").mat().ravel()
            fs.release()
            model = folder.parent / "thermal_opencv.yaml"        # as calibration/formats writes it
            model.write_text(opencv_yaml(Representation("equidistant", K, D, None, "truth"), (640, 512),
                                         camera_name="truth"))
        else:
            model = folder / "truth.cameramodel"
        out[family] = (folder, model)
    return out


@pytest.mark.slow
@pytest.mark.parametrize("family", ["kannala-brandt", "stereographic"])
def test_board_rows_are_straight_after_rectification(rendered, family, tmp_path):
    folder, model = rendered[family]
    out = tmp_path / "rect"
    assert main(["undistort", "--model", str(model), "--images", str(folder), "--out", str(out), "-q"]) == 0
    truth = json.loads((folder / "truth.json").read_text())
    report = json.loads((out / "undistort.json").read_text())
    assert report["pinhole"]["hfov_deg"] == 90.0 and report["images"] == 3
    for im in truth["images"]:
        q = np.array([c if c is not None else [np.nan, np.nan] for c in im["corners"]], float)
        raw_bend = worst_line_px(q, *BOARD)
        rect = cv2.imread(str(out / im["file"]), cv2.IMREAD_UNCHANGED)
        assert rect.dtype == np.uint16 and rect.shape == (512, 640)
        det = detect_corners(rect, BOARD)
        assert det.complete, (im["file"], det.reason)
        straight = worst_line_px(det.corners, *BOARD)
        assert raw_bend > 1.0, (im["file"], raw_bend)          # the raw rows do bend
        assert straight < 0.25, (im["file"], straight)         # the rectified ones do not
    fig = cv2.imread(str(out / "before_after.png"), cv2.IMREAD_UNCHANGED)
    assert fig.dtype == np.uint8 and fig.shape[0] == 512 and fig.shape[1] > 2 * 640


@pytest.fixture
def small_set(tmp_path):
    """A 320x256 stereographic model (written as mrcal writes it) and a folder of one image."""
    from platform_tools.rig.cameras import camera_model
    model = tmp_path / "small.cameramodel"
    camera_model("LENSMODEL_STEREOGRAPHIC", [160.0, 160.0, 159.5, 127.5], (320, 256)).write(str(model))
    folder = tmp_path / "small"
    folder.mkdir()
    cv2.imwrite(str(folder / "a.png"), (np.arange(320 * 256, dtype=np.uint16) % 4000).reshape(256, 320))
    return model, folder


def test_a_small_set_is_rectified(small_set, tmp_path):
    model, folder = small_set
    out = tmp_path / "rect"
    assert main(["undistort", "--model", str(model), "--images", str(folder), "--out", str(out), "-q"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["a.png", "before_after.png", "rectified.cameramodel",
                                                     "undistort.json"]
    assert json.loads((out / "undistort.json").read_text())["projection"].startswith("mrcal.project")


def _one_line(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    return err


def test_bad_model_file_is_one_line_and_nothing_written(small_set, tmp_path, capsys):
    _, folder = small_set
    out = tmp_path / "rect"
    for name, text in (("bad.cameramodel", "{ this is not a model"), ("bad.yaml", "%YAML:1.0\n---\nfoo: 1\n"),
                       ("bad.txt", "hello")):
        model = tmp_path / name
        model.write_text(text)
        assert main(["undistort", "--model", str(model), "--images", str(folder), "--out", str(out)]) == 2
        assert name in _one_line(capsys)
        assert not out.exists()
    assert main(["undistort", "--model", str(tmp_path / "none.cameramodel"), "--images", str(folder),
                 "--out", str(out)]) == 2
    assert "no such model file" in _one_line(capsys)
    assert not out.exists()


def test_empty_folder_or_wrong_size_is_one_line_and_the_old_output_stays(tmp_path, capsys):
    from platform_tools.rig.cameras import camera_model
    model = tmp_path / "big.cameramodel"
    camera_model("LENSMODEL_STEREOGRAPHIC", [320.0, 320.0, 319.5, 255.5], (640, 512)).write(str(model))
    out = tmp_path / "rect"
    out.mkdir()
    (out / "keep.txt").write_text("earlier output")
    empty = tmp_path / "empty"
    empty.mkdir()
    assert main(["undistort", "--model", str(model), "--images", str(empty), "--out", str(out)]) == 2
    assert "no images" in _one_line(capsys)
    small = tmp_path / "small"
    small.mkdir()
    cv2.imwrite(str(small / "a.png"), (np.arange(320 * 256, dtype=np.uint16) % 4000).reshape(256, 320))
    assert main(["undistort", "--model", str(model), "--images", str(small), "--out", str(out)]) == 2
    assert "a.png: 320x256 image" in _one_line(capsys)
    assert main(["undistort", "--model", str(model), "--images", str(small), "--out", str(out), "--fov", "180"]) == 2
    assert "--fov" in _one_line(capsys)
    assert sorted(p.name for p in out.iterdir()) == ["keep.txt"]
