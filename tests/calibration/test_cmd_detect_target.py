"""`calibrate detect --target`: every target through the same detect_target as `calibrate thermal`, written
to corners.vnl and read back by mrcal's own reader (mrcal.compute_chessboard_corners with
corners_cache_vnl: what mrcal-calibrate-cameras --corners-cache runs), checked against the rendered truth.
The images are rendered through the Kannala-Brandt truth lens (closed form, not the solver's family)."""
from __future__ import annotations

import json

import cv2
import mrcal
import numpy as np
import pytest

from calibration.cli import main
from calibration.synth.circles_render import circle_board
from calibration.synth.targets_render import render_views, target_board
from calibration.synth.truth_families import truth_lens
from calibration.targets import marker_block
from calibration.targets.spec import circle_present

N_IMAGES = 3
TARGETS = {  # target: (board, spacing m, how far a reported point may be from its truth: px)
    "checkerboard": ((10, 7), 0.04, 1.0),
    "marker-checkerboard": ((10, 7), 0.04, 1.0),
    "circle-grid": ((7, 5), 0.04, 1.5),              # raw centroids: the bias is up to ~0.5 px
    "asymmetric-circle-grid": ((8, 7), 0.04, 1.5),
}


def absent(target, board):
    """(W*H,) bool: points the target never has (the marker's corners, a lattice point with no disc)."""
    if target == "marker-checkerboard":
        return marker_block(board)
    if target in ("circle-grid", "asymmetric-circle-grid"):
        return ~circle_present(target, board)
    return np.zeros(board[0] * board[1], bool)


def render(tmp_path, target):
    (W, H), s, _ = TARGETS[target]
    b = circle_board(target, W, H, s) if "circle" in target else target_board(target, W, H, s)
    folder = tmp_path / "images"
    folder.mkdir()
    truth = {}
    for k, (img, q, _occ) in enumerate(render_views(truth_lens("kannala-brandt"), b, "easy", n=N_IMAGES, seed=33)):
        cv2.imwrite(str(folder / f"{k:03d}.png"), img)
        truth[f"{k:03d}.png"] = q
    return folder, truth


@pytest.mark.slow
@pytest.mark.parametrize("target", list(TARGETS))
def test_each_target_is_written_as_mrcal_reads_it(tmp_path, capsys, target):
    (W, H), _, tol = TARGETS[target]
    folder, truth = render(tmp_path, target)
    out = tmp_path / "det"
    code = main(["detect", "--images", str(folder), "--board", f"{W}x{H}", "--target", target, "--out", str(out),
                 "--json", "-q"])
    assert code == 0, capsys.readouterr().err
    report = json.loads(capsys.readouterr().out)
    assert report["target"] == target and report["detected"] >= 2, report
    obs, indices, files = mrcal.compute_chessboard_corners(W, H, globs_per_camera=("*.png",),
                                                           corners_cache_vnl=str(out / "corners.vnl"),
                                                           weight_column_kind="level")
    found = {p["file"] for p in report["per_image"] if p["found"]}
    assert sorted(str(f).split("/")[-1] for f in files) == sorted(found)
    never = absent(target, (W, H))
    for name, o in zip(files, obs):
        name = str(name).split("/")[-1]
        xy, w = o[..., :2].reshape(-1, 2), o[..., 2].ravel()
        used = w > 0
        assert not np.any(used & never), "mrcal sees a point the target does not have"
        q = truth[name]
        assert np.all(np.isfinite(q[used, 0])), "a point reported where the truth is out of view"
        err = np.linalg.norm(xy[used] - q[used], axis=1)
        assert used.sum() >= 0.5 * (~never).sum() and err.max() < tol, (name, int(used.sum()), float(err.max()))


def test_a_board_the_target_cannot_have_is_one_line_exit_2(tmp_path, capsys):
    out = tmp_path / "det"
    code = main(["detect", "--images", str(tmp_path), "--board", "7x5", "--target", "asymmetric-circle-grid",
                 "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "patternSize (7, 5) is --board 14x5" in err[0], err
    assert not out.exists()


def test_help_names_the_targets_and_the_exit_codes(capsys):
    with pytest.raises(SystemExit):
        main(["detect", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "asymmetric-circle-grid" in text and "Exit codes: 0" in text and "2 bad input" in text
