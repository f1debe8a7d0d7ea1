"""The export: recordings in, a dataset folder out; resumable, on one core, a process pool or Dask.

Layout of ``OUT``::

    export.json                      what this export is (inputs, parameters, calibration) and its status
    index.csv, index.parquet         one row per sample (written when every chunk is done)
    README.md                        the dataset card (:mod:`.card`), written with the index
    <recording>/zed_left/NNNNNN.jpg          RGB as recorded: a compressed topic's JPEG, byte for byte (a raw
    <recording>/zed_right/NNNNNN.jpg          topic, or processing.zed_images png: NNNNNN.png, 8-bit BGR PNG)
    <recording>/thermal_left/raw16/NNNNNN.png        the 16-bit original
    <recording>/thermal_left/8bit/NNNNNN.png         the paper's 8-bit image
    <recording>/thermal_left/rgb_registered/NNNNNN.png   ZED RGB registered into this view
    <recording>/thermal_left/mask/NNNNNN.png         255 where the registered RGB is valid
    <recording>/thermal_left/depth_mm/NNNNNN.png     registered depth, 16-bit mm (0: none)
    <recording>/thermal_right/...
    .chunks/<recording>-CCCCC.json   one per finished chunk of samples: its index rows

Work is cut into chunks of consecutive samples of one recording. A chunk's images are written
first, then its marker; an interrupted export resumes by redoing only the chunks without a marker (a killed
worker's temporary files are removed first). ``Params.outputs`` chooses the images (``PAPER_OUTPUTS``: the
paper's release).
``export.json`` holds a fingerprint of everything the output depends on: the same command resumes,
a different one (other recordings, rate, calibration, parameters) is refused rather than mixed in.

The pieces: :mod:`.decode` reads the image messages, :mod:`.chunk` does one chunk's work (the same
function on every engine), :mod:`.engines` runs the chunks (``inline``, ``pool``, ``dask``); this module
plans the chunks, keeps the manifest and the resume markers, and writes the index.
"""
from __future__ import annotations

import csv
import hashlib
import io
import json
import logging
import re
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Callable

from platform_tools.rig import atomic
from platform_tools.rig.interrupts import held
from . import card, thermal8
from .calib import CalibrationError, at_recorded_size, for_recording, load_calibration, model_to_dict, zed_right
from .chunk import FILE_COLUMNS, KINDS, TMP_SUFFIX, preload, process_chunk, warm_up
from .decode import IMAGE_STREAMS, probe_sizes
from .engines import ENGINES, EngineError, start_method, started, stdlib_distutils
from .pairing import plan
from .recording import RecordingError, open_recording, read_summaries, telemetry_rows
from .stereo import BUILT_IN, StereoError, load_plugin

log = logging.getLogger(__name__)
FORMAT = "rgbt-rig export 1"
MANIFEST = "export.json"
CHUNKS = ".chunks"


class ExportError(Exception):
    """The export cannot run as asked; one line."""


@dataclass(frozen=True)
class Params:
    rate_hz: float
    tolerance_ms: float
    ffc_margin: int
    keep_ffc: bool
    zbuffer_tolerance_percent: float
    min_coverage: float
    chunk_size: int
    thermal_8bit: dict
    #: "auto" (recorded when the recording has depth, else stereo), "recorded", "stereo" or a "module:function"
    depth: str = "auto"
    #: the images written per sample (chunk.KINDS; PAPER_OUTPUTS for --paper)
    outputs: tuple = KINDS
    #: zlib level of the PNGs, 0..9; None: OpenCV's fast default (processing.png_compression_level)
    png_compression_level: int | None = None
    #: "as_recorded": a compressed ZED image's own bytes (chunk.ZED_IMAGES); "png" (processing.zed_images)
    zed_images: str = "as_recorded"

    @classmethod
    def from_rig(cls, rig, *, rate_hz=None, tolerance_ms=None, ffc_margin=None, keep_ffc=False,
                 min_coverage=0.5, chunk_size=8, depth="auto", outputs=KINDS, png_compression_level="rig",
                 zed_images="rig") -> "Params":
        p = rig.desc.processing
        level = p.png_compression_level if png_compression_level == "rig" else png_compression_level
        return cls(float(rate_hz if rate_hz is not None else p.pair_rate_hz),
                   float(tolerance_ms if tolerance_ms is not None else p.pair_tolerance_ms),
                   int(ffc_margin if ffc_margin is not None else p.ffc_margin_frames), bool(keep_ffc),
                   float(p.zbuffer_tolerance_percent), float(min_coverage), int(chunk_size),
                   asdict(thermal8.Params.from_rig(rig)), str(depth), tuple(outputs),
                   None if level is None else int(level), str(p.zed_images if zed_images == "rig" else zed_images))


#: what the paper releases per sample (docs/dataset.md "The paper's dataset"): per thermal camera its 8-bit image,
#: the RGB registered into it and the mask of where that RGB is valid (no content where there was no depth)
PAPER_OUTPUTS = ("8bit", "rgb_registered", "mask")
#: the paper counts its pairs at 1 Hz (shared/reference/platform.md)
PAPER_RATE_HZ = 1.0


# ----------------------------------------------------------------------------- the export
def _fingerprint(manifest: dict) -> str:
    keep = {k: manifest[k] for k in ("format", "recordings", "params", "calibration", "rig_hash")}
    return hashlib.sha256(json.dumps(keep, sort_keys=True, default=str).encode()).hexdigest()


def _differences(old: dict, new: dict) -> list[str]:
    diffs = []
    if [r.get("fingerprint") for r in old.get("recordings", [])] != [r["fingerprint"] for r in new["recordings"]]:
        diffs.append("recordings " + ", ".join(r.get("path", "?") for r in old.get("recordings", [])))
    for k, v in new["params"].items():
        if json.dumps(old.get("params", {}).get(k), default=str) != json.dumps(v, default=str):
            diffs.append(f"{k} {old.get('params', {}).get(k)}")
    if old.get("calibration", {}).get("sha256") != new["calibration"]["sha256"]:
        diffs.append(f"calibration {old.get('calibration', {}).get('source')}")
    if old.get("rig_hash") != new["rig_hash"] and not diffs:
        diffs.append("rig description")
    return diffs or ["format"]


def chunk_spans(n: int, size: int) -> list[tuple[int, int]]:
    """The ``[start, end)`` sample ranges of one recording's chunks: ``size`` samples each, but the last ones halve
    (``size // 2`` twice, ``size // 4`` twice, ... one sample twice) and the first takes what is left over. The pool
    hands chunks out in this order, so the workers' last chunks are small and end close together: with chunks of
    8 samples all alike, one worker sat idle for up to a chunk (0.6 s of a 14 s export measured, docs/dataset.md
    "Speed"). A function of ``n`` and ``size`` only, both in the export's fingerprint, so a resumed export cuts its
    chunks as the first run did."""
    if n < 1:
        return []
    tail, piece = [], size // 2
    while piece >= 1:
        tail += [piece, piece]
        piece //= 2
    sizes, left = [], n                         # built from the end: the smallest pieces last
    for piece in reversed(tail):
        if not left:
            break
        sizes.append(min(piece, left))
        left -= sizes[-1]
    while left:
        sizes.append(min(size, left))
        left -= sizes[-1]
    spans, start = [], 0
    for k in reversed(sizes):
        spans.append((start, start + k))
        start += k
    return spans


def _chunk_complete(out: Path, marker: Path, samples: list[int]) -> bool:
    """A chunk is done when its marker reads, holds the rows of exactly its task's ``samples`` (a marker an export cut
    otherwise wrote is redone, not taken for this chunk), and every image it lists is still there."""
    try:
        rows = json.loads(marker.read_text())
    except (OSError, json.JSONDecodeError):
        return False
    if not isinstance(rows, list) or [r.get("sample") if isinstance(r, dict) else None for r in rows] != samples:
        return False
    return all((out / v).is_file() for r in rows for k, v in r.items() if k.endswith(FILE_COLUMNS) and v)


#: a chunk writer's temporary image (chunk.tmp_name): ``.NNNNNN.png.PID.tmp`` or ``.NNNNNN.jpg.PID.tmp``
_PARTIAL = re.compile(r"^\.\d{6}\.(png|jpg)\.\d+" + re.escape(TMP_SUFFIX) + "$")
#: the files export writes itself with platform_tools.rig.atomic, whose temporary files are ``.NAME.XXXXXXXX.tmp``
_OWN = (MANIFEST, "index.csv", "index.parquet", card.CARD)


def _atomic_tmp(name_re: str) -> re.Pattern:
    return re.compile(r"^\." + name_re + r"\.[A-Za-z0-9_]+\.tmp$")


def remove_partial(out: Path, recordings) -> list[Path]:
    """Remove what a stopped or killed export left half-written in its own folder: a worker's temporary images
    (the names chunk.tmp_name makes) in the recording folders, and the temporary files of export's own atomic
    writes (a chunk marker, the manifest, the index, the card). Returns them."""
    gone = []
    checks = [(out / name, _PARTIAL, True) for name in recordings]
    checks += [(out / CHUNKS, _atomic_tmp(r"[^/]+\.json"), False)]
    checks += [(out, _atomic_tmp("|".join(re.escape(n) for n in _OWN)), False)]
    for folder, pattern, deep in checks:
        if not folder.is_dir():
            continue
        for f in (folder.rglob if deep else folder.glob)("*.tmp"):
            if pattern.match(f.name) and f.is_file():
                f.unlink(missing_ok=True)
                gone.append(f)
    return gone


def check_out(out: Path, manifest: dict) -> dict | None:
    """The existing manifest to resume, None for a new export; refuses a folder holding anything else."""
    if not out.exists():
        return None
    if not out.is_dir():
        raise ExportError(f"{out}: exists and is not a folder")
    m = out / MANIFEST
    if not m.is_file():
        if any(out.iterdir()):
            raise ExportError(f"{out}: not empty and holds no export ({MANIFEST} missing); nothing was written: "
                              f"choose an empty or new --out")
        return None
    try:
        old = json.loads(m.read_text())
    except (OSError, json.JSONDecodeError) as exc:
        raise ExportError(f"{m}: unreadable ({exc}); nothing was written: choose another --out") from None
    if old.get("fingerprint") != manifest["fingerprint"]:
        raise ExportError(f"{out}: holds a different export (it had: {'; '.join(_differences(old, manifest))}); "
                          f"nothing was written: choose another --out, or delete that folder to redo it")
    return old


def export(recordings: list[Path], out: Path, rig, params: Params, *, calibration: Path | None = None,
           engine: str = "pool", workers: int = 1, scheduler: str | None = None, recover: bool = False,
           on_chunk: Callable[[str], None] | None = None, topic_map=None, command: list[str] | None = None) -> dict:
    """``calibration``: a folder of models overriding the recordings' camera_info and the nominal models;
    ``topic_map``: a :class:`.layout.Layout` (``--topics``) instead of the detected layout; ``command``: the
    command line, for the dataset card. A pool's workers start first (engines.started), scan the recordings' chunks
    for the index (recording.open_recording ``pool``), load their kernels while this process plans, and run the
    chunks."""
    if engine == "pool" and workers > 1:
        try:
            start_method()
        except EngineError as exc:
            raise ExportError(str(exc)) from None
    with stdlib_distutils():
        import mrcal  # noqa: F401 - the calibration's, imported without setuptools (engines.stdlib_distutils)
    for path in recordings:                 # before the fork: forked workers inherit them (recording.read_summaries)
        read_summaries(path)
    with started(engine, workers, warm_up, preload) as pool:
        return _export(recordings, out, rig, params, calibration=calibration, engine=engine, workers=workers,
                       scheduler=scheduler, recover=recover, on_chunk=on_chunk, topic_map=topic_map,
                       command=command, pool=pool)


def _export(recordings, out, rig, params, *, calibration, engine, workers, scheduler, recover, on_chunk, topic_map,
            command, pool) -> dict:
    out = Path(out)
    if params.depth not in BUILT_IN:
        try:
            load_plugin(params.depth)
        except StereoError as exc:
            raise ExportError(str(exc)) from None
    try:
        fixed = load_calibration(rig, calibration) if calibration is not None else None
    except CalibrationError as exc:
        raise ExportError(str(exc)) from None
    recs, plans, tasks_by_rec, idents, cals = [], [], [], [], []
    names = set()
    rig_hash = rig.hash                     # the whole description serialised and hashed: once, not per chunk
    for path in recordings:
        try:
            rec = open_recording(path, rig, recover=recover, topic_map=topic_map, pool=pool)
            recorded_depth = params.depth == "recorded" or (params.depth == "auto" and rec.has("zed_depth"))
            depth = "recorded" if recorded_depth else "stereo" if params.depth in BUILT_IN else params.depth
            pl = plan(rec, rig, rate_hz=params.rate_hz, tolerance_ms=params.tolerance_ms,
                      ffc_margin=params.ffc_margin, keep_ffc=params.keep_ffc, depth=recorded_depth)
            cal = fixed or for_recording(rig, rec)
            right = None if recorded_depth else zed_right(rig, rec, calibration)
        except (RecordingError, CalibrationError, EngineError) as exc:
            raise ExportError(str(exc)) from None
        if rec.name in names:
            raise ExportError(f"{path}: two recordings named {rec.name!r}; give each a distinct folder name")
        names.add(rec.name)
        sizes = probe_sizes(rec)
        w, h = sizes["thermal_left"]
        th_h = h - telemetry_rows(rig, w, h)   # Boson telemetry rows below the image: not part of the picture
        if recorded_depth and sizes["zed_depth"] != sizes["zed_left"]:
            raise ExportError(f"{rec.path}: the depth is {sizes['zed_depth'][0]}x{sizes['zed_depth'][1]}, the ZED "
                              f"left image {sizes['zed_left'][0]}x{sizes['zed_left'][1]}: depth_registered must "
                              f"be at the image's size")
        recorded = {"zed_x_left_optical": sizes["zed_left"], "thermal_left_optical": (w, th_h),
                    "thermal_right_optical": (sizes["thermal_right"][0], th_h)}
        try:
            cams = {n: at_recorded_size(n, cal.cams[n], size, str(rec.path)) for n, size in recorded.items()}
            if right is not None:
                cams["zed_x_right_optical"] = at_recorded_size("zed_x_right_optical", right, sizes["zed_right"],
                                                               str(rec.path))
        except CalibrationError as exc:
            raise ExportError(str(exc)) from None
        recs.append(rec)
        plans.append(pl)
        cals.append(cal)
        idents.append(rec.identity() | {"offsets_ms": pl.offsets_ms, "clock_steps": pl.clock_steps,
                                        "counts": pl.counts, "layout": rec.layout, "depth": depth,
                                        "calibration": {"source": cal.source, "sha256": cal.sha256}})
        topics = {s: rec.streams[s].topic for s in IMAGE_STREAMS if s != "zed_depth" or recorded_depth}
        chunks = []
        for k, (c0, c1) in enumerate(chunk_spans(len(pl.pairs), params.chunk_size)):
            pairs = [asdict(p) for p in pl.pairs[c0:c1]]
            chunks.append({"id": f"{rec.name}-{k:05d}", "recording": rec.name,
                           "files": [str(f.resolve()) for f in rec.files], "topics": topics, "pairs": pairs,
                           "cams": {n: model_to_dict(m) for n, m in cams.items()},
                           "thermal_height": th_h, "params": asdict(params), "out": str(out.resolve()),
                           "depth": depth,
                           "calibration_source": cal.source, "calibration_sha256": cal.sha256,
                           "rig_hash": rig_hash})
        tasks_by_rec.append(chunks)
    calibration_used = _calibration_used(cals)
    manifest = {"format": FORMAT, "recordings": [{k: v for k, v in i.items() if k != "clock_steps"} | {
        "clock_steps": i["clock_steps"]} for i in idents],
        "params": asdict(params), "calibration": calibration_used, "rig_hash": rig_hash}
    manifest["fingerprint"] = _fingerprint(manifest)
    old = check_out(out, manifest)
    remove_partial(out, names)            # what a stopped or killed run left half-written
    out.mkdir(parents=True, exist_ok=True)
    (out / CHUNKS).mkdir(exist_ok=True)
    tasks = [t for ch in tasks_by_rec for t in ch]
    todo = [t for t in tasks if not _chunk_complete(out, out / CHUNKS / f"{t['id']}.json",
                                                    [p["sample"] for p in t["pairs"]])]
    models = (cals[0].to_dict() if len({c.sha256 for c in cals}) == 1
              else {"per_recording": {r.name: c.to_dict() for r, c in zip(recs, cals)}})
    manifest |= {"status": "running", "calibration_models": models,
                 "chunks": len(tasks), "samples": sum(len(t["pairs"]) for t in tasks)}
    with held():
        atomic.write_text(out / MANIFEST, json.dumps(manifest, indent=2) + "\n")
    resumed = old is not None and len(todo) < len(tasks)
    if resumed:
        log.warning("%s: resuming: %d of %d chunks already done", out, len(tasks) - len(todo), len(tasks))

    def finished(task: dict, rows: list[dict]) -> None:
        with held():
            atomic.write_text(out / CHUNKS / f"{task['id']}.json", json.dumps(rows) + "\n")
        if on_chunk:
            on_chunk(task["id"])

    run = ENGINES.get(engine)
    if run is None:
        raise ExportError(f"engine {engine!r}: expected {', '.join(ENGINES)}")
    if todo:
        try:
            run(process_chunk, todo, finished, workers, scheduler, pool)
        except (EngineError, RecordingError, StereoError) as exc:
            raise ExportError(str(exc)) from None
        finally:                          # interrupted: the workers are stopped; their unfinished files go
            remove_partial(out, names)
    rows = []
    for t in tasks:
        rows += json.loads((out / CHUNKS / f"{t['id']}.json").read_text())
    text = card.render(manifest, rows, command)
    with held():
        write_index(out, rows)
        atomic.write_text(out / card.CARD, text)
        manifest |= {"status": "complete", "rows": len(rows)}
        atomic.write_text(out / MANIFEST, json.dumps(manifest, indent=2) + "\n")
    return {"out": str(out), "samples": len(rows), "chunks": len(tasks), "chunks_run": len(todo),
            "resumed": resumed, "engine": engine, "workers": workers, "recordings": idents,
            "calibration": calibration_used}


def _calibration_used(cals: list) -> dict:
    """The manifest's calibration: the one every recording used, or each recording's, hashed together."""
    if len({c.sha256 for c in cals}) == 1:
        return {"source": cals[0].source, "sha256": cals[0].sha256}
    return {"source": " | ".join(dict.fromkeys(c.source for c in cals)),
            "sha256": hashlib.sha256("".join(c.sha256 for c in cals).encode()).hexdigest()}


# ----------------------------------------------------------------------------- the index
def write_index(out: Path, rows: list[dict]) -> None:
    rows = sorted(rows, key=lambda r: (r["recording"], r["sample"]))
    cols: list[str] = []
    for r in rows:
        cols += [k for k in r if k not in cols]
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=cols, lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: ("" if r.get(k) is None else r.get(k)) for k in cols})
    atomic.write_text(out / "index.csv", buf.getvalue())
    import pyarrow as pa
    import pyarrow.parquet as pq
    table = pa.table({c: [r.get(c) for r in rows] for c in cols})
    sink = io.BytesIO()
    pq.write_table(table, sink)
    atomic.write_bytes(out / "index.parquet", sink.getvalue())
