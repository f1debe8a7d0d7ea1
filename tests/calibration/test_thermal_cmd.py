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
    assert stdout, (code, err)
    summary = json.loads(stdout)
    # 12 easy images leave the bottom-right image corner without a board: solved, but not trusted
    assert code == 1 and "calibration not trusted" in err, err
    grade = summary["verdict"]["grade"]
    assert grade == "not-trusted" and summary["verdict"]["trustworthy"] is False
    assert "the bottom-right corner has no data" in summary["verdict"]["headline"]
    assert 0.4 <= summary["verdict"]["trusted_share"] < 0.8          # measured 0.55
    assert summary["rms_px"] < 0.1                                    # corners: 0.013 px RMS reprojection
    for name in ("thermal.cameramodel", "thermal_opencv.yaml", "thermal_camera_info.yaml",
                 "kalibr_camchain.yaml", "corners.vnl", "report.html"):
        assert (out / name).is_file(), name
    m = mrcal.cameramodel(str(out / "thermal.cameramodel"))
    # thermal.cameramodel is mrcal's own solve (OPENCV8, or OPENCV5 where OPENCV8 folds: see
    # calibration/thermal/lens_choice.py), or the nearest OPENCV8 to a chosen Kannala-Brandt (then
    # without mrcal's optimization inputs)
    assert summary["lensmodel"] in ("LENSMODEL_OPENCV8", "LENSMODEL_OPENCV5", "KANNALA_BRANDT")
    assert m.intrinsics()[0] == ("LENSMODEL_OPENCV8" if summary["lensmodel"] == "KANNALA_BRANDT"
                                 else summary["lensmodel"])
    assert (m.optimization_inputs() is not None) == (summary["lensmodel"] != "KANNALA_BRANDT")
    assert m.valid_intrinsics_region() is not None          # where cross-validation trusts it
    assert summary["cross_validation"] is not None and 0 <= summary["validity"]["trusted_share"] <= 1
    # a 95 deg lens goes to ROS as equidistant (image_geometry inverts it exactly; see test_formats.py)
    assert yaml.safe_load((out / "thermal_camera_info.yaml").read_text())["distortion_model"] == "equidistant"
    # every exported file was read back by its own tool and checked over the whole image
    assert set(summary["lens_health"]) == {"thermal.cameramodel", "thermal_opencv.yaml",
                                           "thermal_camera_info.yaml", "kalibr_camchain.yaml"}
    assert all(h["ok"] for h in summary["lens_health"].values()), summary["lens_health"]
    assert any("lens model chosen by the data: held-out views" in n for n in summary["notes"]), summary["notes"]
    assert (out / "corners.vnl").read_text().startswith("# filename x y level")
    assert summary["n_images_used"] >= 10

    code, stdout, err = run(capsys, "validate", str(out / "thermal.cameramodel"), "--truth", str(src), "--json")
    v = json.loads(stdout)
    # the figures against the truth (measured: 2.25 px RMS over the whole image, where the corners are
    # extrapolation; 0.10 px over the central 80%; 0.025 px inside the valid-intrinsics region): a wrong
    # model (a wrong lens, focal length or board) is pixels off in the centre and fails every bound
    assert code == 1 and v["within_targets"] is False
    assert v["central80_rms_px"] < 0.2, v
    assert v["rms_px"] < 5.0, v
    assert max(abs(e) for e in v["focal_error_px"] + v["principal_point_error_px"]) < 0.5, v
    truth = mrcal.cameramodel(str(src / "truth.cameramodel"))
    assert _rms_in_valid_region(m, truth) < 0.1
    # and the verdict never calls a model trusted that is far from the truth
    assert grade != "trusted" or v["rms_px"] <= 0.3

    # the wrong board size (the board is larger): bad input naming the size the views show, exit 2,
    # the previous output untouched (was exit 1, "too little to solve", before the set-level check of
    # calibration/detect/batch.board_size_problem)
    before = sorted(p.name for p in out.iterdir())
    code, _, err = run(capsys, "thermal", "--images", str(src), "--board", "9x9", "--square", "0.04",
                       "--out", str(out))
    assert code == 2 and "larger than the --board 9x9" in err and "e.g. --board 10x" in err, err
    assert sorted(p.name for p in out.iterdir()) == before


def _rms_in_valid_region(model, truth) -> float:
    """RMS projection difference against the truth inside the model's valid-intrinsics region (the
    rotation fitted over the central 80%: a model used within its region is aligned there)."""
    from calibration.lens.compare import compare_models
    c = compare_models(model, truth, grid_width=32, fit_fraction=0.8)
    region = model.valid_intrinsics_region()
    if region is None or len(region) < 4:
        return 0.0          # nothing is claimed
    inside = np.array([mrcal.is_within_valid_intrinsics_region(q, model) for q in c.grid.reshape(-1, 2)])
    d = c.diff_px.reshape(-1)[inside]
    return float(np.sqrt(np.mean(d ** 2))) if d.size else 0.0


def test_exit_code_follows_the_grade():
    from calibration.report.verdict import Verdict
    from calibration.commands.thermal import accepted
    for grade, default, whole in [("trusted", True, True), ("trusted-within-region", True, False),
                                  ("not-trusted", False, False)]:
        v = Verdict(grade)
        assert accepted(v) is default and accepted(v, require_whole_image=True) is whole, grade


@pytest.fixture
def graded(monkeypatch):
    """calibrate thermal with its verdict forced to a grade (the solve and the outputs are real)."""
    from calibration.thermal import outputs
    from calibration.report.verdict import Verdict
    forced = {}

    def judge(**kw):
        return Verdict(forced["grade"], reasons=["forced"] if forced["grade"] == "not-trusted" else [],
                       trusted_share=0.9, limits=["the top-left corner has no data"])
    monkeypatch.setattr(outputs, "judge", judge)
    return forced


@pytest.mark.slow
def test_exit_codes_of_each_grade_and_require_whole_image(synth_set, tmp_path, capsys, graded):
    src = synth_set("easy", n=12, seed=4)
    base = ("thermal", "--images", str(src), "--board", "10x7", "--square", "0.04", "--out", str(tmp_path / "o"))
    for grade, flags, want in [("trusted-within-region", (), 0),
                               ("trusted-within-region", ("--require-whole-image",), 1),
                               ("trusted-within-region", ("--require-whole-image", "--exit-zero"), 0),
                               ("trusted", ("--require-whole-image",), 0),
                               ("not-trusted", (), 1),
                               ("not-trusted", ("--exit-zero",), 0)]:
        graded["grade"] = grade
        code, stdout, err = run(capsys, *base, *flags, "--json")
        assert code == want, (grade, flags, err)
        summary = json.loads(stdout)
        assert summary["verdict"]["grade"] == grade
        assert summary["verdict"]["trustworthy"] == (grade != "not-trusted")
        page = (tmp_path / "o" / "report.html").read_text()
        assert f'data-grade="{grade}"' in page
        style = {"trusted": "ok", "trusted-within-region": "partial", "not-trusted": "bad"}[grade]
        assert f'class="verdict {style}"' in page
        if code:
            assert len(err.strip().splitlines()) == 1
            assert ("--require-whole-image" in err) == (grade == "trusted-within-region"), err
    graded["grade"] = "trusted-within-region"
    code, stdout, _ = run(capsys, *base)
    assert code == 0 and "trusted within its valid region (90% of the image): the top-left corner has no data" in stdout


def test_help_names_the_grades_and_exit_codes(capsys):
    with pytest.raises(SystemExit):
        main(["thermal", "--help"])
    out = " ".join(capsys.readouterr().out.split())
    for s in ("--require-whole-image", "trusted-within-region", "not-trusted", "Exit codes: 0 trusted or "
              "trusted-within-region; 1 not-trusted"):
        assert s in out, s


def test_validate_bad_input(tmp_path, capsys):
    (tmp_path / "x.cameramodel").write_text("not a model")
    code, _, err = run(capsys, "validate", str(tmp_path / "x.cameramodel"), "--truth", str(tmp_path))
    assert code == 2 and "x.cameramodel" in err


def test_marker_target_on_a_board_too_small_for_its_marker(tmp_path, capsys):
    code, _, err = run(capsys, "thermal", "--images", str(tmp_path), "--board", "4x7", "--square", "0.04",
                       "--target", "marker-checkerboard", "--out", str(tmp_path / "out"))
    assert code == 2 and "--board 4x7" in err and "at least 5x5" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
def test_marker_checkerboard_end_to_end(tmp_path, capsys):
    """14 views of a 10x7 marker board through the Kannala-Brandt truth lens ("real"), written as
    16-bit PNGs and calibrated with --target marker-checkerboard: solved from the marker-labelled
    corners, the marker's own corners absent from corners.vnl, the focal length and centre of the
    Kannala-Brandt truth recovered."""
    from calibration.synth.targets_render import MarkerBoard, render_views
    from calibration.synth.truth_families import truth_lens
    from calibration.targets import marker_block
    lens = truth_lens("kannala-brandt")
    src = tmp_path / "imgs"
    src.mkdir()
    for k, (img, _, _) in enumerate(render_views(lens, MarkerBoard(10, 7, 0.04), "real", n=14, seed=31)):
        cv2.imwrite(str(src / f"{k:03d}.png"), img)
    out = tmp_path / "out"
    code, stdout, err = run(capsys, "thermal", "--images", str(src), "--board", "10x7", "--square", "0.04",
                            "--target", "marker-checkerboard", "--out", str(out), "--json", "-q", "--exit-zero")
    assert code == 0 and stdout, err
    summary = json.loads(stdout)
    assert summary["n_images_used"] >= 10 and summary["rms_px"] < 0.1, summary
    rows = [r.split() for r in (out / "corners.vnl").read_text().splitlines() if not r.startswith("#")]
    per_image = {}
    for r in rows:
        per_image.setdefault(r[0], []).append(r[1] != "-")
    block = marker_block((10, 7))
    for name, seen in per_image.items():
        if len(seen) == 70:
            assert not np.any(np.array(seen)[block]), f"{name}: a marker corner in corners.vnl"
    m = mrcal.cameramodel(str(out / "thermal.cameramodel"))
    fx, fy, cx, cy = m.intrinsics()[1][:4]
    assert abs(fx - lens.fx) < 2.0 and abs(fy - lens.fy) < 2.0, (fx, fy, lens.fx, lens.fy)
    assert abs(cx - lens.cx) < 3.0 and abs(cy - lens.cy) < 3.0, (cx, cy, lens.cx, lens.cy)
