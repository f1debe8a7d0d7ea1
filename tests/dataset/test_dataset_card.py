"""`export --paper`: the dataset as the paper releases it (1 Hz pairs, 8-bit thermal, RGB registered into each
thermal view, its mask) and the dataset card (README.md) whose numbers are checked against the output's files,
the bag's own message counts (read by the mcap library, not the export's index), the simulator's truth and an
export of every image kind made separately."""
from __future__ import annotations

import csv
import json
import math
import shlex
from pathlib import Path

import numpy as np
import pytest

from platform_tools.dataset.card import CARD, table
from platform_tools.dataset.export import PAPER_OUTPUTS, Params, export
from tests.conftest import run_tool
from tests.dataset.pngsame import same_file

pytestmark = pytest.mark.slow
KINDS = [f"{cam}_{k}" for cam in ("thermal_left", "thermal_right") for k in PAPER_OUTPUTS]


@pytest.fixture(scope="module")
def paper(sim, tmp_path_factory):
    out = tmp_path_factory.mktemp("paper") / "ds"
    args = ["export", str(sim[0]), "--out", str(out), "--paper", "--workers", "2"]
    r = run_tool("platform_tools.cli.main", *args, timeout=1200)
    assert r.returncode == 0, r.stderr
    with open(out / "index.csv") as f:
        rows = list(csv.DictReader(f))
    return out, rows, (out / CARD).read_text(), args


def test_only_the_papers_images_are_written(paper):
    out, rows, _, _ = paper
    rec = rows[0]["recording"]
    folders = sorted(str(p.relative_to(out / rec)) for p in (out / rec).glob("*/*") if p.is_dir())
    assert folders == sorted(f"{cam}/{k}" for cam in ("thermal_left", "thermal_right") for k in PAPER_OUTPUTS)
    assert not (out / rec / "zed_left").exists()
    assert {k for k in rows[0] if k.endswith("_png")} == {f"{k}_png" for k in KINDS}


def test_the_card_counts_what_is_on_disk(paper, sim):
    out, rows, text, _ = paper
    rec = rows[0]["recording"]
    on_disk = {k: len(list((out / rec).glob(f"{k.split('_', 2)[0]}_{k.split('_', 2)[1]}/{k.split('_', 2)[2]}/*.png")))
               for k in KINDS}
    for k in KINDS:
        assert int(table(text, k)[0]) == on_disk[k] == len(rows)
    assert int(table(text, "total")[0]) == len(list(out.rglob("*.png")))
    # the recording's row: samples as in the index; ZED left frames as the bag's own statistics count them
    layout, depth, zed_frames, complete, ffc_dropped, samples = table(text, rec)
    assert (layout, depth, int(samples)) == ("project", "recorded", len(rows))
    from mcap.reader import make_reader
    with open(next((sim[0] / "bag").glob("*.mcap")), "rb") as f:
        summary = make_reader(f).get_summary()
    counts = {c.topic: summary.statistics.channel_message_counts[i] for i, c in summary.channels.items()}
    assert int(zed_frames) == counts["/zed/zed_node/left/image_rect_color/compressed"]
    assert int(complete) <= int(zed_frames) and 0 < int(ffc_dropped) < int(complete)   # the sim has FFC
    # 1 Hz: one sample per whole second of the recording at most, as the truth's duration allows
    assert len(rows) <= math.floor(sim[1]["params"]["duration_s"]) + 1 and "(1 Hz)" in text


def test_the_cards_sync_statistics_are_the_index_and_the_truth(paper, sim):
    out, rows, text, _ = paper
    rec = rows[0]["recording"]
    truth = sim[1]
    for cam in ("thermal_left", "thermal_right"):
        assert abs(float(table(text, f"{rec} {cam}")[0]) - truth["offsets_ms"][cam]) < 0.5
        r = np.array([float(x[f"residual_{cam}_ms"]) for x in rows])
        n, mean, std, p99, mx = table(text, f"residual {cam}")
        a = np.sort(np.abs(r))
        assert int(n) == len(r)
        assert abs(float(mean) - r.mean()) < 6e-4 and abs(float(std) - r.std()) < 6e-4
        assert abs(float(p99) - a[math.ceil(0.99 * len(a)) - 1]) < 6e-4 and abs(float(mx) - a[-1]) < 6e-4
    step = truth["clock_step"]["step_ns"] / 1e6
    assert f"Clock steps taken out: 1 ({rec}: {step:+.1f} ms)" in text


def test_the_card_names_the_calibration_and_the_command(paper):
    out, rows, text, args = paper
    manifest = json.loads((out / "export.json").read_text())
    assert f"Source: {rows[0]['calibration']}" in text
    assert f"sha256: `{rows[0]['calibration_sha256']}`" in text and all(
        r["calibration_sha256"] == rows[0]["calibration_sha256"] for r in rows)
    models = manifest["calibration_models"]["cameras"]
    assert table(text, "thermal_left_optical")[0] == models["thermal_left_optical"]["lensmodel"]
    # the command as given: the same words (options in the card's fixed order), runnable as it stands
    given = text.split("## Command", 1)[1].split("```")[1].strip()
    assert sorted(shlex.split(given)) == sorted(["platform_tools"] + args)


def test_the_papers_images_are_those_of_the_full_export(paper, sim, rig, tmp_path):
    out, rows, _, _ = paper
    full = tmp_path / "full"
    export([sim[0]], full, rig, Params.from_rig(rig), engine="inline")
    with open(full / "index.csv") as f:
        full_rows = list(csv.DictReader(f))
    assert [r["t_zed_left_ns"] for r in full_rows] == [r["t_zed_left_ns"] for r in rows]
    for a, b in zip(rows, full_rows):
        for k in KINDS:
            assert same_file(a[f"{k}_png"], (out / a[f"{k}_png"]).read_bytes(),
                             (full / b[f"{k}_png"]).read_bytes()), k       # the same scanlines (pngsame.py)


def test_paper_refuses_another_rate_and_a_bad_png_level(sim, tmp_path):
    for extra, what in ((["--paper", "--rate", "2"], "--paper --rate 2"), (["--png-level", "12"], "--png-level 12")):
        out = tmp_path / "x"
        r = run_tool("platform_tools.cli.main", "export", str(sim[0]), "--out", str(out), *extra)
        assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1 and what in r.stderr, r.stderr
        assert not out.exists()
