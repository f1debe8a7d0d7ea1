"""The dataset card: ``README.md`` in an export folder, saying what the dataset is, from the export's own manifest
and index rows (never from a second count): the recordings, how many samples and files of each kind, the sync
statistics, the calibration used and its source, how the pairs were made, and the command line.

:func:`render` is a pure function of (manifest, rows, command); export writes its text atomically beside the index.
The tables' first column is a key, so a script (and the tests) can read a number back: :func:`table`.
"""
from __future__ import annotations

import math
import shlex

CARD = "README.md"
#: the residual columns of the index whose statistics the card gives (ms after the camera's trigger offset)
RESIDUALS = ("thermal_left", "thermal_right", "zed_right", "zed_depth")


def _fmt(x) -> str:
    if x is None:
        return "-"
    if isinstance(x, float):
        return f"{x:.3f}"
    return str(x)


def _stats(values: list[float]) -> dict:
    """n, mean, std, p99 of |v| and max |v| (ms)."""
    v = sorted(values)
    n = len(v)
    if not n:
        return {"n": 0, "mean": None, "std": None, "p99_abs": None, "max_abs": None}
    mean = sum(v) / n
    a = sorted(abs(x) for x in v)
    return {"n": n, "mean": mean, "std": math.sqrt(sum((x - mean) ** 2 for x in v) / n),
            "p99_abs": a[min(n - 1, math.ceil(0.99 * n) - 1)], "max_abs": a[-1]}


def _table(head: list[str], body: list[list]) -> list[str]:
    out = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    out += ["| " + " | ".join(_fmt(c) for c in r) + " |" for r in body]
    return out + [""]


def files_by_kind(rows: list[dict]) -> dict[str, int]:
    """Image files the index lists, per kind (the column name less ``_png`` or ``_jpg``, chunk.FILE_COLUMNS)."""
    from .chunk import FILE_COLUMNS
    out: dict[str, int] = {}
    for r in rows:
        for k, v in r.items():
            if k.endswith(FILE_COLUMNS) and v:
                kind = k[:-len("_png")]
                out[kind] = out.get(kind, 0) + 1
    return out


def render(manifest: dict, rows: list[dict], command: list[str] | None) -> str:
    p = manifest["params"]
    recs = manifest["recordings"]
    by_rec: dict[str, list[dict]] = {}
    for r in rows:
        by_rec.setdefault(r["recording"], []).append(r)
    paper = tuple(p.get("outputs") or ()) == ("8bit", "rgb_registered", "mask")
    lines = [f"# Dataset card: {len(rows)} registered RGB-thermal samples from {len(recs)} recording(s)", "",
             "Written by `platform_tools export` (" + manifest["format"] + ") of the rgbt-rig project; "
             + ("the paper's release: 1 Hz pairs, 8-bit thermal, RGB registered into each thermal view, and "
                "its validity mask." if paper else "every image kind of the export."), "",
             "## Command", "", "```",
             shlex.join(command) if command else "(called from Python: platform_tools.dataset.export.export)",
             "```", "", "## Recordings", ""]
    body = []
    for i in recs:
        c = i["counts"]
        body.append([i["name"], i.get("layout"), i.get("depth"), c["zed_left_frames"], c["complete"],
                     c["ffc_dropped"], len(by_rec.get(i["name"], []))])
    lines += _table(["recording", "layout", "depth", "ZED left frames", "complete pairs", "dropped for FFC",
                     "samples"], body)
    lines += ["Source files: " + "; ".join(f"`{i['name']}`: {i['path']}" for i in recs), "",
              "## Files", ""]
    kinds = files_by_kind(rows)
    lines += _table(["kind", "files"], [[k, n] for k, n in kinds.items()] + [["total", sum(kinds.values())]])
    lines += ["Each sample's files are listed in `index.csv` / `index.parquet` (the same rows), with the stamps "
              "of its frames, the residuals below, FFC flags and the 8-bit bounds.", "",
              "## Sync", "",
              "Each Boson frame is paired with the ZED frame of the trigger pulse that exposed it (offsets below: "
              "each camera's stamp after the ZED left's, clock steps taken out); a residual is what remains of a "
              "pair's stamp difference after that offset.", ""]
    body = []
    for i in recs:
        for cam, off in sorted(i.get("offsets_ms", {}).items()):
            body.append([f"{i['name']} {cam}", off])
    lines += _table(["recording camera", "offset (ms)"], body)
    steps = [(i["name"], s) for i in recs for s in i.get("clock_steps", [])]
    lines += [f"Clock steps taken out: {len(steps)}" + ("" if not steps else " (" + "; ".join(
        f"{n}: {s['step_ns'] / 1e6:+.1f} ms" for n, s in steps) + ")"), ""]
    body = []
    for cam in RESIDUALS:
        vals = [float(r[f"residual_{cam}_ms"]) for r in rows if r.get(f"residual_{cam}_ms") not in (None, "")]
        if vals:
            s = _stats(vals)
            body.append([f"residual {cam}", s["n"], s["mean"], s["std"], s["p99_abs"], s["max_abs"]])
    lines += _table(["pair residual (ms)", "n", "mean", "std", "p99 abs", "max abs"], body)
    lines += ["## Calibration", ""]
    cal = manifest["calibration"]
    lines += [f"Source: {cal['source']}", "", f"sha256: `{cal['sha256']}` (the full models are in `export.json`, "
              "`calibration_models`)", ""]
    models = manifest.get("calibration_models", {})
    per = models.get("per_recording", {"": models})
    body = []
    for rec, m in per.items():
        for cam, d in sorted(m.get("cameras", {}).items()):
            body.append([f"{rec} {cam}".strip(), d.get("lensmodel"), "x".join(map(str, d.get("imagersize", [])))])
    if body:
        lines += _table(["camera", "lens model", "calibrated at (px; scaled to the recorded size)"], body)
    t8 = p["thermal_8bit"]
    lines += ["## How the pairs were made", "",
              f"- Sampling: one sample per {1 / p['rate_hz']:g} s slot ({p['rate_hz']:g} Hz), the valid pair "
              f"nearest the slot; a pair is valid when every residual is within {p['tolerance_ms']:g} ms.",
              f"- FFC: thermal frames during a flat-field correction, and {p['ffc_margin']} frames on each side, "
              + ("kept and flagged." if p["keep_ffc"] else "dropped."),
              f"- 16 -> 8 bit as the paper (FIReStereo `process_image`): min-max, percentile clip "
              f"{t8['percentile_low']:g}-{t8['percentile_high']:g} % when the maximum reaches "
              f"{t8['clip_above_counts']} counts, CLAHE {t8['clahe_clip_limit']:g} / {t8['clahe_tile_grid']}x"
              f"{t8['clahe_tile_grid']}, bilateral {t8['bilateral_d']} / {t8['bilateral_sigma_color']:g} / "
              f"{t8['bilateral_sigma_space']:g}.",
              f"- Registration: every ZED left pixel back-projected with its depth ("
              + ", ".join(sorted({str(i.get("depth")) for i in recs})) + "), moved into the thermal camera with the "
              f"calibration's extrinsics, projected with its lens; z-buffer tolerance "
              f"{p['zbuffer_tolerance_percent']:g} %, bilinear splatting, a pixel valid (mask 255) with at least "
              f"{p['min_coverage']:g} of a fully covered pixel's weight; no colour where there was no depth.",
              "- PNG: " + ("the export's own writer (ISA-L deflate level 1, UP filter)"
                           if p.get("png_compression_level") is None
                           else f"OpenCV's libpng, zlib level {p['png_compression_level']}") + ".",
              "- ZED images: " + ("decoded and written as PNG" if p.get("zed_images") == "png" else
                                  "as recorded: a compressed topic's JPEG byte for byte (`*_jpg` columns), a raw "
                                  "topic as PNG") + ".", ""]
    return "\n".join(lines)


def table(text: str, key: str) -> list[str]:
    """The cells (after the first) of the card's table row whose first cell is ``key``."""
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if line.startswith("|") and cells[0] == key:
            return cells[1:]
    raise KeyError(key)
