"""`calibrate thermal` and `calibrate validate` as a user runs them: outputs, exit codes, bad input."""
from __future__ import annotations

import json
import shutil

import cv2
import mrcal
import numpy as np
import pytest
import yaml

from calibration.cli import main


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_empty_folder_is_bad_input_and_writes_nothing(tmp_path, capsys):
    (tmp_path / "imgs").mkdir()
    code, _, err = run(capsys, "thermal", "--images", str(tmp_path / "imgs"), "--board", "10x7",
                       "--square", "0.04", "--out", str(tmp_path / "out"))
    assert code == 2 and "no images" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


def test_corrupt_and_saturated_images(tmp_path, capsys):
    d = tmp_path / "imgs"
    d.mkdir()
    for i in range(3):
        cv2.imwrite(str(d / f"{i:03d}.png"), np.full((512, 640), 65535, np.uint16))
    code, _, err = run(capsys, "thermal", "--images", str(d), "--board", "10x7", "--square", "0.04",
                       "--out", str(tmp_path / "out"))
    assert code == 2 and "saturated" in err and "none of the 3 images" in err
    (d / "bad.png").write_bytes(b"\x89PNG not really")
    code, _, err = run(capsys, "thermal", "--images", str(d), "--board", "10x7", "--square", "0.04",
                       "--out", str(tmp_path / "out"))
    assert code == 2 and "bad.png" in err
    assert not (tmp_path / "out").exists()


def test_bad_square_and_lens_model(tmp_path, capsys):
    code, _, err = run(capsys, "thermal", "--images", str(tmp_path), "--board", "10x7", "--square", "40",
                       "--out", str(tmp_path / "out"))
    assert code == 2 and "--square" in err
    code, _, err = run(capsys, "thermal", "--images", str(tmp_path), "--board", "10x7", "--square", "0.04",
                       "--lens-model", "nonsense", "--out", str(tmp_path / "out"))
    assert code == 2 and "--lens-model" in err


@pytest.mark.slow
def test_calibrate_validate_end_to_end_and_wrong_board(synth_set, tmp_path, capsys):
    src = synth_set("easy", n=12, seed=4)
    out = tmp_path / "out"
    code, stdout, err = run(capsys, "thermal", "--images", str(src), "--board", "10x7", "--square", "0.04",
                            "--out", str(out), "--json", "-q")
    summary = json.loads(stdout)
    assert code in (0, 1), err
    assert (code == 0) == summary["verdict"]["trustworthy"]
    for name in ("thermal.cameramodel", "thermal_opencv.yaml", "thermal_camera_info.yaml",
                 "kalibr_camchain.yaml", "corners.vnl", "report.html"):
        assert (out / name).is_file(), name
    m = mrcal.cameramodel(str(out / "thermal.cameramodel"))
    assert m.optimization_inputs() is not None and m.intrinsics()[0] == "LENSMODEL_OPENCV8"
    assert m.valid_intrinsics_region() is not None          # where cross-validation trusts it
    assert summary["cross_validation"] is not None and 0 <= summary["validity"]["trusted_share"] <= 1
    assert yaml.safe_load((out / "thermal_camera_info.yaml").read_text())["distortion_model"] == "rational_polynomial"
    assert (out / "corners.vnl").read_text().startswith("# filename x y level")
    assert summary["n_images_used"] >= 10

    code, stdout, err = run(capsys, "validate", str(out / "thermal.cameramodel"), "--truth", str(src), "--json")
    v = json.loads(stdout)
    assert code == (0 if v["within_targets"] else 1)
    # the verdict must never call a calibration trustworthy that is far from the truth
    if v["rms_px"] > 0.3:
        assert not summary["verdict"]["trustworthy"], (v, summary["verdict"])

    # the wrong board size: nothing found, exit 1, the previous output untouched
    before = sorted(p.name for p in out.iterdir())
    code, _, err = run(capsys, "thermal", "--images", str(src), "--board", "9x9", "--square", "0.04",
                       "--out", str(out))
    assert code == 1 and "--board" in err
    assert sorted(p.name for p in out.iterdir()) == before


def test_validate_bad_input(tmp_path, capsys):
    (tmp_path / "x.cameramodel").write_text("not a model")
    code, _, err = run(capsys, "validate", str(tmp_path / "x.cameramodel"), "--truth", str(tmp_path))
    assert code == 2 and "x.cameramodel" in err
