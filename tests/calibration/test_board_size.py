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
