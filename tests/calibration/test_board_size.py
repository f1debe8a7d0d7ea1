"""A board larger than --board (docs/calibration-synthetic.md, known limits): a view with the whole
board is refused with the size found (grid.orient), but a partial view sees one edge only and labels
W x H corners from it, so a left-anchored and a right-anchored view name different board corners alike.
No single view can tell; the set can (calibration/detect/batch.board_size_problem): when views show
the larger grid, `calibrate detect` and `calibrate thermal` refuse the whole set, naming the size.

Images: this project's renderer through the Kannala-Brandt truth lens (not the solver's family),
'real', a 10x7 board, seed 5: 000 and 001 whole, 002 (columns 0-7 in view) and 004 (columns 3-9)
partial."""
from __future__ import annotations

import json

import numpy as np
import pytest

from calibration.cli import main


@pytest.fixture(scope="module")
def ten_by_seven(tmp_path_factory):
    from calibration.synth import render_dataset
    from calibration.synth.truth_families import truth_lens
    out = tmp_path_factory.mktemp("big") / "set"
    render_dataset(out, n=20, difficulty="real", board=(10, 7), square=0.04, seed=5,
                   lens=truth_lens("kannala-brandt"), show_progress=False, only=[0, 1, 2, 4])
    for extra in ("truth.json", "truth.cameramodel", "truth_table.npz", "truth_fisheye.yaml"):
        (out / extra).rename(out.parent / extra) if (out / extra).exists() else None
    return out, json.loads((out.parent / "truth.json").read_text())


@pytest.mark.slow
@pytest.mark.parametrize("command", ["detect", "thermal"])
def test_a_set_of_a_larger_board_is_refused_with_the_size_found(ten_by_seven, tmp_path, capsys, command):
    """Under --board 9x7 the two whole views are refused as 10x7 and the two partial ones would be
    labelled (measured: 002 from its left edge, 004 from its right, so their column 3 is the board's
    column 3 in one and 4 in the other): the set is refused, one line, exit 2, nothing written."""
    folder, _ = ten_by_seven
    out = tmp_path / "out"
    args = [command, "--images", str(folder), "--board", "9x7", "--out", str(out)]
    if command == "thermal":
        args += ["--square", "0.04"]
    code = main(args + ["--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2, err
    assert len(err) == 1 and "2 of 4 views" in err[0] and "--board 10x7" in err[0], err
    assert not out.exists()


@pytest.mark.slow
def test_the_right_board_size_is_not_refused(ten_by_seven, tmp_path, capsys):
    folder, _ = ten_by_seven
    code = main(["detect", "--images", str(folder), "--board", "10x7", "--out", str(tmp_path / "out"), "--json"])
    assert code == 0, capsys.readouterr().err
    assert (tmp_path / "out" / "corners.vnl").is_file()


# ---------------------------------------------------------------- the larger board never seen whole
# Partial views only: a 10x7 board held so that each view cuts one side off (columns 0-8 or 0-7 in
# view with the left edge, 1-9 with the right edge), and one view with all ten columns, both side edges
# and the top rows cut off. Under --board 9x7 every partial view is labelled (9 or fewer columns, one
# edge), the right-edge ones a column off the left-edge ones, and the one ten-column view is refused on
# its own: fewer than larger_problem needs. What refuses the set is the labels (anchoring_problem):
# views placed by opposite edges, and no view showing both. Images: this project's renderer through the
# Kannala-Brandt truth lens (not the solver's family), 'real', poses below, seed 3.
# name: (centre x, centre y as image shares, board width / image width, tilt, roll, tilt axis; deg)
PARTIAL_VIEWS = {
    "left_a": (0.85, 0.5, 0.55, 15, 4, 17), "left_b": (0.88, 0.4, 0.6, 20, -5, 69),
    "right_a": (0.15, 0.5, 0.55, 15, -3, 29), "right_b": (0.12, 0.6, 0.6, 20, 5, 143),
    "across": (0.5, 0.08, 0.6, 8, 2, 57)}


def held_view(lens, board, cx, cy, width, tilt_deg, roll_deg, axis_deg):
    """A BoardView of ``board`` facing the camera at image point (cx W, cy H), ``width`` of the image
    wide, tilted about an in-plane axis and rolled (the truth lens' own closed-form unprojection)."""
    from calibration.synth.poses import BoardView, project_corners
    from platform_tools.rig.frames import rotvec_to_matrix
    W, H = lens.size
    v = lens.unproject(np.array([[cx * W, cy * H]], float))[0]
    v = v / np.linalg.norm(v)
    x = np.array([1.0, 0.0, 0.0]) - v[0] * v
    x /= np.linalg.norm(x)
    R = np.stack([x, np.cross(v, x), v], axis=1)
    a = np.radians(axis_deg)
    R = rotvec_to_matrix((R[:, 0] * np.cos(a) + R[:, 1] * np.sin(a)) * np.radians(tilt_deg)) @ R \
        @ rotvec_to_matrix(np.array([0.0, 0.0, np.radians(roll_deg)]))
    t = lens.fx * (board.width + 1) * board.square_m / (width * W) * v - R @ board.centre()
    return BoardView(R, t, project_corners(lens, board, R, t), True)


@pytest.fixture(scope="module")
def partial_only(tmp_path_factory):
    """folder of the five views (NAME.png) and the true corners {name: (70, 2) px, NaN out of view}."""
    import cv2

    from calibration.synth.board import Board
    from calibration.synth.targets_render import render_views
    from calibration.synth.truth_families import truth_lens
    lens, board = truth_lens("kannala-brandt"), Board(10, 7, 0.04)
    views = [held_view(lens, board, *spec) for spec in PARTIAL_VIEWS.values()]
    out = tmp_path_factory.mktemp("partial") / "set"
    out.mkdir()
    truth = {}
    for name, (img, corners, _) in zip(PARTIAL_VIEWS, render_views(lens, board, "real", views=views, seed=3)):
        cv2.imwrite(str(out / f"{name}.png"), img)
        truth[name] = corners
    return out, truth


def columns_rows_in_view(corners):
    seen = np.isfinite(corners[:, 0]).reshape(7, 10)
    return np.flatnonzero(seen.any(axis=0)).tolist(), np.flatnonzero(seen.any(axis=1)).tolist()


def label_offsets(det, truth):
    """{(true i - label i, true j - label j)} of every corner of ``det`` (its nearest true corner)."""
    W, _ = det.board
    k = np.flatnonzero(np.isfinite(det.corners[:, 0]))
    d = np.linalg.norm(truth[None] - det.corners[k][:, None], axis=2)
    t = np.nanargmin(d, axis=1)
    assert np.nanmin(d, axis=1).max() < 1.0
    return {(int(a), int(b)) for a, b in zip(t % 10 - k % W, t // 10 - k // W)}


@pytest.mark.slow
def test_the_partial_views_are_what_they_are_meant_to_be(partial_only):
    """The data and the mislabel the check exists for: no partial view has all ten columns, each keeps
    the edge its name says and every row; the 'across' view has all ten columns but not every row.
    Under --board 9x7 each partial view is labelled, the right-edge ones a column off the truth."""
    import cv2

    from calibration.detect import detect_corners
    folder, truth = partial_only
    for name, corners in truth.items():
        cols, rows = columns_rows_in_view(corners)
        if name == "across":
            assert cols == list(range(10)) and len(rows) < 7, (name, cols, rows)
            continue
        assert len(cols) <= 9 and rows == list(range(7)), (name, cols, rows)
        assert (cols[0] == 0) == name.startswith("left") and (cols[-1] == 9) == name.startswith("right")
        det = detect_corners(cv2.imread(str(folder / f"{name}.png"), cv2.IMREAD_UNCHANGED), (9, 7))
        assert det.detected, (name, det.reason)
        assert label_offsets(det, corners) == ({(1, 0)} if name.startswith("right") else {(0, 0)}), name


@pytest.mark.slow
@pytest.mark.parametrize("command", ["detect", "thermal"])
def test_partial_views_of_a_larger_board_are_refused_as_ambiguous(partial_only, tmp_path, capsys, command):
    folder, _ = partial_only
    out = tmp_path / "out"
    args = [command, "--images", str(folder), "--board", "9x7", "--out", str(out), "--quiet"]
    code = main(args + (["--square", "0.04"] if command == "thermal" else []))
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2, err
    assert len(err) == 1 and "ambiguous labels: 2 view(s) placed by the board's left edge and 2 by its right" in err[0]
    assert "1 view(s) show a grid of corners larger than 9x7 (up to 10x5)" in err[0] and "--board 10x7" in err[0], err
    assert not out.exists()


@pytest.mark.slow
def test_the_right_board_on_the_same_views_passes_with_the_true_labels(partial_only, tmp_path, capsys):
    from calibration.formats.corners_vnl import read_corners
    folder, truth = partial_only
    out = tmp_path / "out"
    code = main(["detect", "--images", str(folder), "--board", "10x7", "--out", str(out), "--quiet"])
    assert code == 0, capsys.readouterr().err
    rows = {r.filename[:-4]: r for r in read_corners(out / "corners.vnl", 70)}
    assert sorted(rows) == sorted(truth) and all(r.corners is not None for r in rows.values())
    for name, r in rows.items():
        ok = np.isfinite(r.corners[:, 0])
        assert ok.sum() >= 40
        assert np.linalg.norm(r.corners[ok] - truth[name][ok], axis=1).max() < 0.5, name   # every label true


@pytest.mark.slow
@pytest.mark.parametrize("board", ["9x7", "10x7"])
def test_a_set_that_cannot_tell_the_board_size_is_refused_under_any_board(partial_only, tmp_path, capsys, board):
    """Without the 'across' view the four partial views fit a 9x7 board and a 10x7 one alike."""
    import shutil
    folder, _ = partial_only
    some = tmp_path / "set"
    some.mkdir()
    for p in folder.glob("*.png"):
        if p.stem != "across":
            shutil.copy(p, some)
    out = tmp_path / "out"
    code = main(["detect", "--images", str(some), "--board", board, "--out", str(out), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    n = board.split("x")[0]
    assert f"ambiguous labels: 2 view(s) placed by the board's left edge and 2 by its right edge name the same " \
           f"corners only if the board has exactly {n} inner corners across" in err[0], err
    assert "add a view that shows the whole board across (its left and right edges)" in err[0], err
    assert not out.exists()


@pytest.mark.slow
def test_thermal_stereo_refuses_a_camera_whose_views_cannot_tell_the_board(partial_only, tmp_path, capsys):
    """The pair's solve gives both cameras' views of a pose one board pose, so labels from opposite
    edges would put one board in two places: `calibrate thermal-stereo` judges each camera's views as
    `calibrate thermal` does (here the same five images in both folders; models: any 640x512 pair)."""
    import shutil

    from calibration.synth.truth_families import truth_lens
    from calibration.synth.truth_files import write_cameramodel
    folder, _ = partial_only
    for side in ("left", "right"):
        shutil.copytree(folder, tmp_path / "set" / side)
        write_cameramodel(tmp_path / f"{side}.cameramodel", truth_lens("stereographic"), f"{side} model")
    out = tmp_path / "out"
    code = main(["thermal-stereo", "--left", str(tmp_path / "left.cameramodel"), "--right",
                 str(tmp_path / "right.cameramodel"), "--images", str(tmp_path / "set"), "--board", "9x7",
                 "--square", "0.04", "--out", str(out), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert f"{tmp_path / 'set' / 'left'}: ambiguous labels: 2 view(s) placed by the board's left" in err[0], err
    assert "--board 10x7" in err[0] and err[0].endswith("nothing written"), err
    assert not out.exists()


@pytest.mark.parametrize("sizes, board, expected", [
    ([(10, 5)], (9, 7), (10, 7)),             # a partial grid of the larger board: its rows are not all seen
    ([(10, 5), (8, 7)], (9, 7), (10, 7)),
    ([(10, 7)], (7, 9), (7, 10)),             # --board given down x across: the suggestion follows it
    ([(7, 7)], (6, 7), (7, 7)),
])
def test_the_size_suggested_holds_every_grid_found_in_the_orientation_given(sizes, board, expected):
    from calibration.detect.batch import suggested_board
    assert suggested_board(sizes, board) == expected
