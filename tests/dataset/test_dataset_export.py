"""`platform_tools export`: pairs, FFC filtering, sampling, the paper's 8-bit thermal, registered RGB,
the index, resuming, refusing a different export, and the same result on every engine."""
from __future__ import annotations

import csv
import json
import shutil

import cv2
import numpy as np
import pytest

from platform_tools.dataset import thermal8
from platform_tools.dataset.export import ExportError, Params, chunk_spans, export
from platform_tools.sim import geometry

#: every test exports a simulated recording: the quick loop (make test-fast) leaves them to make test
pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def done(sim, rig, tmp_path_factory):
    out = tmp_path_factory.mktemp("export") / "ds"
    summary = export([sim[0]], out, rig, Params.from_rig(rig, chunk_size=2), engine="inline")
    return out, summary


def rows(out):
    with open(out / "index.csv") as f:
        return list(csv.DictReader(f))


@pytest.mark.slow
def test_index_pairs_rate_and_ffc(done, sim, rig):
    out, summary = done
    _, truth = sim
    r = rows(out)
    assert summary["samples"] == len(r) >= 4
    import pyarrow.parquet as pq
    table = pq.read_table(out / "index.parquet").to_pylist()
    assert [str(t["t_zed_left_ns"]) for t in table] == [x["t_zed_left_ns"] for x in r]
    period = 1e9 / truth["rate_hz"]
    margin = rig.desc.processing.ffc_margin_frames
    for x in r:
        for cam in ("thermal_left", "thermal_right"):
            t = int(x[f"t_{cam}_ns"])
            for e in truth["ffc"]:
                if e["camera"] == cam:    # the FFC and its neighbours (margin frames each side) are gone
                    assert not (e["start_ns"] - (margin - 1) * period <= t < e["end_ns"] + (margin - 1) * period)
            assert x[f"{cam}_ffc"] == "False"
            assert abs(float(x[f"residual_{cam}_ms"])) <= rig.desc.processing.pair_tolerance_ms
        assert x["calibration"].startswith("nominal") and len(x["calibration_sha256"]) == 64
    slots = [int(x["sample"]) for x in r]
    assert slots == sorted(set(slots))          # one per second at most, in order
    manifest = json.loads((out / "export.json").read_text())
    assert manifest["status"] == "complete" and manifest["rows"] == len(r)
    assert manifest["calibration_models"]["cameras"]["thermal_left_optical"]["lensmodel"] == "LENSMODEL_STEREOGRAPHIC"


def test_images_16bit_kept_and_8bit_as_the_paper(done, rig):
    out, _ = done
    p = thermal8.Params.from_rig(rig)
    for x in rows(out)[:3]:
        for cam in ("thermal_left", "thermal_right"):
            raw = cv2.imread(str(out / x[f"{cam}_raw16_png"]), cv2.IMREAD_UNCHANGED)
            assert raw.dtype == np.uint16 and raw.max() > 7000
            img8 = cv2.imread(str(out / x[f"{cam}_8bit_png"]), cv2.IMREAD_UNCHANGED)
            assert np.array_equal(img8, thermal8.to_8bit(raw, p)[0])
            assert int(x[f"{cam}_lo_counts"]) == int(raw.min()) and int(x[f"{cam}_hi_counts"]) == int(raw.max())


def test_registered_rgb_matches_the_scene_seen_by_the_thermal_camera(done, sim, rig):
    out, _ = done
    _, truth = sim
    period = 1e9 / truth["rate_hz"]
    step = truth["clock_step"]
    x = rows(out)[1]
    t = int(x["t_zed_left_ns"])
    t_true = t - (step["step_ns"] if t >= step["true_ns"] + step["step_ns"] else 0)
    k = round((t_true - truth["params"]["start_ns"]) / period)          # the trigger pulse
    cam = truth["cameras"]["thermal_left"]
    th = geometry.sim_camera(rig, cam["frame"], *cam["size"])
    boxes = geometry.boxes_at(truth["scene"], k / truth["rate_hz"])
    render = geometry.cast(th, geometry.rays_rig(th), boxes)
    want = geometry.colour(render, boxes, truth["scene"]).astype(float)
    got = cv2.imread(str(out / x["thermal_left_rgb_registered_png"])).astype(float)
    mask = cv2.imread(str(out / x["thermal_left_mask_png"]), cv2.IMREAD_UNCHANGED) > 0
    assert mask.mean() > 0.3
    # per surface, away from its outline (the checker is finer than these small images' pixels):
    # the registered colour is the colour of the surface the thermal camera sees there
    checked = 0
    for i, b in enumerate(boxes):
        inside = cv2.erode((render.which == i).astype(np.uint8), np.ones((3, 3), np.uint8)) > 0
        sel = inside & mask
        if sel.sum() < 20:
            continue
        assert np.abs(got[sel].mean(0) - want[sel].mean(0)).max() < 12, b.name
        checked += 1
    assert checked >= 3


def test_interrupted_export_resumes(done, sim, rig, tmp_path):
    out = tmp_path / "ds"
    seen = []

    def stop_after_first(chunk_id):
        seen.append(chunk_id)
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        export([sim[0]], out, rig, Params.from_rig(rig, chunk_size=2), engine="inline", on_chunk=stop_after_first)
    assert json.loads((out / "export.json").read_text())["status"] == "running"
    assert not (out / "index.csv").exists()
    s = export([sim[0]], out, rig, Params.from_rig(rig, chunk_size=2), engine="inline")
    assert s["resumed"] and s["chunks_run"] == s["chunks"] - 1
    assert (out / "index.csv").read_text() == (done[0] / "index.csv").read_text()


def test_markers_of_another_chunk_cutting_are_redone_not_taken(done, sim, rig, tmp_path):
    """An export begun by code that cut its chunks otherwise (every chunk 2 samples, before export.chunk_spans halved
    the last ones) resumes with each sample once: a marker is taken only when it holds exactly its chunk's samples."""
    out = tmp_path / "ds"
    shutil.copytree(done[0], out)
    (out / "index.csv").unlink()
    by_sample = {}
    for marker in sorted((out / ".chunks").glob("*.json")):
        by_sample |= {row["sample"]: row for row in json.loads(marker.read_text())}
        marker.unlink()
    samples = sorted(by_sample)
    new = [samples[a:b] for a, b in chunk_spans(len(samples), 2)]
    rest = samples[len(new[0]):]
    old = [new[0]] + [rest[i:i + 2] for i in range(0, len(rest), 2)]   # the first chunk alike, then 2, 2, ... (or 1)
    for k, group in enumerate(old):
        (out / ".chunks" / f"{sim[0].name}-{k:05d}.json").write_text(json.dumps([by_sample[s] for s in group]))
    taken = sum(1 for k, group in enumerate(new) if k < len(old) and old[k] == group)
    assert new != old and 0 < taken < len(new)                            # some markers fit their chunk, some not
    s = export([sim[0]], out, rig, Params.from_rig(rig, chunk_size=2), engine="inline")
    assert s["resumed"] and s["chunks"] == len(new) and s["chunks_run"] == len(new) - taken
    assert (out / "index.csv").read_text() == (done[0] / "index.csv").read_text()


def test_a_folder_holding_a_different_export_is_refused(done, sim, rig, tmp_path):
    out = tmp_path / "copy"
    shutil.copytree(done[0], out)
    before = {p: p.stat().st_mtime_ns for p in out.rglob("*")}
    with pytest.raises(ExportError, match="holds a different export.*rate_hz 1.0"):
        export([sim[0]], out, rig, Params.from_rig(rig, rate_hz=2, chunk_size=2), engine="inline")
    assert {p: p.stat().st_mtime_ns for p in out.rglob("*")} == before
    other = tmp_path / "other"
    other.mkdir()
    (other / "notes.txt").write_text("mine")
    with pytest.raises(ExportError, match="not empty and holds no export"):
        export([sim[0]], other, rig, Params.from_rig(rig), engine="inline")
    assert [p.name for p in other.iterdir()] == ["notes.txt"]


@pytest.mark.slow
@pytest.mark.parametrize("engine", ["pool", "dask"])
def test_engines_give_the_same_dataset(done, sim, rig, tmp_path, engine):
    if engine == "dask":
        pytest.importorskip("distributed")
    out = tmp_path / engine
    s = export([sim[0]], out, rig, Params.from_rig(rig, chunk_size=2), engine=engine, workers=2)
    assert s["chunks_run"] == s["chunks"] > 1
    assert (out / "index.csv").read_text() == (done[0] / "index.csv").read_text()
    a = cv2.imread(str(out / rows(out)[0]["thermal_right_rgb_registered_png"]))
    b = cv2.imread(str(done[0] / rows(done[0])[0]["thermal_right_rgb_registered_png"]))
    assert np.array_equal(a, b)


@pytest.mark.slow
def test_command(platform_tools, sim, tmp_path):
    r = platform_tools("export", str(sim[0]), "--out", str(tmp_path / "ds"), "--rate", "2", "--json")
    assert r.returncode == 0, r.stderr
    s = json.loads(r.stdout)
    assert s["samples"] >= 8 and (tmp_path / "ds" / "index.parquet").is_file()
    r = platform_tools("export", str(sim[0]), "--out", str(tmp_path / "ds"), "--rate", "2")
    assert r.returncode == 0 and "0 of" in r.stdout
    r = platform_tools("export", str(sim[0]), "--out", str(tmp_path / "ds"), "--rate", "0")
    assert r.returncode == 2 and "--rate" in r.stderr
