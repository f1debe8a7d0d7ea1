"""The export: recordings in, a dataset folder out; resumable, on one core, a process pool or Dask.

Layout of ``OUT``::

    export.json                      what this export is (inputs, parameters, calibration) and its status
    index.csv, index.parquet         one row per sample (written when every chunk is done)
    <recording>/zed_left/NNNNNN.png          RGB as recorded (8-bit BGR PNG)
    <recording>/zed_right/NNNNNN.png
    <recording>/thermal_left/raw16/NNNNNN.png        the 16-bit original
    <recording>/thermal_left/8bit/NNNNNN.png         the paper's 8-bit image
    <recording>/thermal_left/rgb_registered/NNNNNN.png   ZED RGB registered into this view
    <recording>/thermal_left/mask/NNNNNN.png         255 where the registered RGB is valid
    <recording>/thermal_left/depth_mm/NNNNNN.png     registered depth, 16-bit mm (0: none)
    <recording>/thermal_right/...
    .chunks/<recording>-CCCCC.json   one per finished chunk of samples: its index rows

Work is cut into chunks of consecutive samples of one recording. A chunk's images are written
first, then its marker; an interrupted export resumes by redoing only the chunks without a marker.
``export.json`` holds a fingerprint of everything the output depends on: the same command resumes,
a different one (other recordings, rate, calibration, parameters) is refused rather than mixed in.

Engines: ``inline`` (one process), ``pool`` (concurrent.futures process pool), ``dask``
(dask.distributed: a LocalCluster, or a running scheduler by address; workers must see the
recordings and OUT at the same paths, e.g. a shared file system). The chunk function
:func:`process_chunk` is the same in all three.
"""
from __future__ import annotations

import csv
import hashlib
import io
import json
import logging
import os
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Callable

import cv2
import numpy as np

from platform_tools.rig import atomic
from platform_tools.rig.progress import progress
from platform_tools.boson.telemetry import telemetry_rows_present
from . import thermal8
from .calib import FRAME_OF, Calibration, CalibrationError, CameraCal, load_calibration
from .pairing import THERMAL, plan
from .recording import Recording, RecordingError, header_stamp, open_recording

log = logging.getLogger(__name__)
FORMAT = "rgbt-rig export 1"
MANIFEST = "export.json"
CHUNKS = ".chunks"
IMAGE_STREAMS = ("zed_left", "zed_right", "zed_depth", "thermal_left", "thermal_right")


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

    @classmethod
    def from_rig(cls, rig, *, rate_hz=None, tolerance_ms=None, ffc_margin=None, keep_ffc=False,
                 min_coverage=0.5, chunk_size=8) -> "Params":
        p = rig.desc.processing
        return cls(float(rate_hz if rate_hz is not None else p.pair_rate_hz),
                   float(tolerance_ms if tolerance_ms is not None else p.pair_tolerance_ms),
                   int(ffc_margin if ffc_margin is not None else p.ffc_margin_frames), bool(keep_ffc),
                   float(p.zbuffer_tolerance_percent), float(min_coverage), int(chunk_size),
                   asdict(thermal8.Params.from_rig(rig)))


# ----------------------------------------------------------------------------- decoding
def decode_image(schema_name: str, msg) -> np.ndarray:
    if schema_name.endswith("CompressedImage"):
        img = cv2.imdecode(np.frombuffer(bytes(msg.data), np.uint8), cv2.IMREAD_UNCHANGED)
        if img is None:
            raise ValueError(f"undecodable {msg.format} image")
        return cv2.cvtColor(img, cv2.COLOR_GRAY2BGR) if img.ndim == 2 else img[..., :3]
    dtypes = {"mono16": (np.uint16, 1), "16UC1": (np.uint16, 1), "32FC1": (np.float32, 1), "mono8": (np.uint8, 1),
              "8UC1": (np.uint8, 1), "bgr8": (np.uint8, 3), "rgb8": (np.uint8, 3), "bgra8": (np.uint8, 4)}
    if msg.encoding not in dtypes:
        raise ValueError(f"unsupported image encoding {msg.encoding!r}")
    dt, ch = dtypes[msg.encoding]
    dt = np.dtype(dt).newbyteorder(">" if msg.is_bigendian else "<")
    row = np.frombuffer(bytes(msg.data), np.uint8).reshape(msg.height, msg.step)
    img = row[:, :msg.width * ch * dt.itemsize].copy().view(dt).reshape(msg.height, msg.width, ch)
    img = img.astype(dt.newbyteorder("="))
    if msg.encoding == "rgb8":
        img = img[..., ::-1]
    return img[..., 0] if ch == 1 else np.ascontiguousarray(img[..., :3])


def _iter_frames(files: list[str], wanted: dict[tuple[str, int], str], lo_ns: int, hi_ns: int):
    """Decode the wanted (topic, header stamp) messages logged within [lo, hi] of the given files."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    topics = sorted({t for t, _ in wanted})
    factory, decoders = DecoderFactory(), {}
    for f in files:
        with open(f, "rb") as fh:
            reader = make_reader(fh)
            try:        # mcap >= 1.3 names the window bounds; older releases take start_time / end_time
                messages = reader.iter_messages(topics=topics, starting_at=lo_ns, ending_at=hi_ns)
            except TypeError:
                messages = reader.iter_messages(topics=topics, start_time=lo_ns, end_time=hi_ns + 1)
            for schema, channel, msg in messages:
                key = (channel.topic, header_stamp(msg.data))
                if key not in wanted:
                    continue
                dec = decoders.get((f, schema.id))
                if dec is None:
                    dec = decoders[(f, schema.id)] = factory.decoder_for("cdr", schema)
                yield wanted[key], key[1], decode_image(schema.name, dec(msg.data))


def probe_sizes(rec: Recording) -> dict[str, tuple[int, int]]:
    """(width, height) of the first message of each image stream."""
    out = {}
    for s in IMAGE_STREAMS:
        st = rec.streams[s]
        i = int(np.argmin(st.log_ns))
        wanted = {(st.topic, int(st.stamp_ns[i])): s}
        for _, _, img in _iter_frames([str(rec.files[st.file_index[i]])], wanted, int(st.log_ns[i]),
                                      int(st.log_ns[i])):
            out[s] = (img.shape[1], img.shape[0])
            break
    return out


# ----------------------------------------------------------------------------- one chunk
_registrars: dict = {}


def _registrar(task: dict, side: str):
    from .register import Registrar
    key = (task["calibration_sha256"], side, json.dumps(task["cams"], sort_keys=True))
    if key not in _registrars:
        cams = {n: CameraCal(n, c["lensmodel"], np.array(c["intrinsics"]), tuple(c["imagersize"]),
                             np.array(c["rt_cam_ref"])) for n, c in task["cams"].items()}
        cal = Calibration("", task["calibration_sha256"], cams)
        frame = FRAME_OF[side]
        _registrars[key] = Registrar(cams["zed_x_left_optical"], cams[frame],
                                     cal.rt_a_b(frame, "zed_x_left_optical"),
                                     task["params"]["zbuffer_tolerance_percent"], task["params"]["min_coverage"])
    return _registrars[key]


def _write_png(path: Path, img: np.ndarray) -> None:
    ok, buf = cv2.imencode(".png", img)
    if not ok:
        raise OSError(f"{path}: PNG encoding failed")
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_bytes(buf.tobytes())
    os.replace(tmp, path)


def process_chunk(task: dict) -> list[dict]:
    """Decode, convert, register and write one chunk of samples; return their index rows."""
    cv2.setNumThreads(1)
    out = Path(task["out"])
    rec_dir = out / task["recording"]
    p8 = thermal8.Params(**task["params"]["thermal_8bit"])
    wanted, lo, hi = {}, None, None
    for pi, pair in enumerate(task["pairs"]):
        for s, fr in pair["frames"].items():
            wanted[(task["topics"][s], fr["stamp_ns"])] = (pi, s)
            lo = fr["log_ns"] if lo is None else min(lo, fr["log_ns"])
            hi = fr["log_ns"] if hi is None else max(hi, fr["log_ns"])
    files = sorted({task["files"][fr["file"]] for p in task["pairs"] for fr in p["frames"].values()})
    images: dict[int, dict[str, np.ndarray]] = {}
    for (pi, s), _, img in _iter_frames(files, wanted, lo, hi):
        images.setdefault(pi, {})[s] = img
    rows = []
    thermal_h = task["thermal_height"]
    for pi, pair in enumerate(task["pairs"]):
        got = images.get(pi, {})
        missing = [s for s in pair["frames"] if s not in got]
        if missing:
            raise ExportError(f"{task['recording']} sample {pair['sample']}: {', '.join(missing)} not found in "
                              f"the MCAP (changed since it was indexed?)")
        name = f"{pair['sample']:06d}.png"
        row = {"recording": task["recording"], "sample": pair["sample"]}
        for s in IMAGE_STREAMS:
            row[f"t_{s}_ns"] = pair["frames"][s]["stamp_ns"]
        for s, r in pair["residual_ms"].items():
            row[f"residual_{s}_ms"] = round(r, 4)
        zed = got["zed_left"]
        _write_png(rec_dir / "zed_left" / name, zed)
        _write_png(rec_dir / "zed_right" / name, got["zed_right"])
        row["zed_left_png"] = f"{task['recording']}/zed_left/{name}"
        row["zed_right_png"] = f"{task['recording']}/zed_right/{name}"
        depth = got["zed_depth"]
        for cam in THERMAL:
            raw = got[cam]
            if raw.shape[0] > thermal_h:          # Boson telemetry rows appended below the image
                raw = raw[:thermal_h]
            img8, info = thermal8.to_8bit(raw, p8)
            reg = _registrar(task, cam).register(depth, zed)
            d = cam
            _write_png(rec_dir / d / "raw16" / name, raw.astype(np.uint16))
            _write_png(rec_dir / d / "8bit" / name, img8)
            _write_png(rec_dir / d / "rgb_registered" / name, reg.image_u8())
            _write_png(rec_dir / d / "mask" / name, reg.mask.astype(np.uint8) * 255)
            _write_png(rec_dir / d / "depth_mm" / name,
                       np.clip(np.nan_to_num(reg.depth_m * 1000.0, nan=0.0), 0, 65535).astype(np.uint16))
            row |= {f"{cam}_ffc": pair["ffc"][cam], f"{cam}_ffc_status": pair["ffc_status"][cam],
                    f"{cam}_since_ffc_s": pair["since_ffc_s"][cam],
                    f"{cam}_lo_counts": info["lo_counts"], f"{cam}_hi_counts": info["hi_counts"],
                    f"{cam}_percentile_clip": info["percentile_clip"],
                    f"{cam}_registered_fraction": round(float(reg.mask.mean()), 4)}
            for kind in ("raw16", "8bit", "rgb_registered", "mask", "depth_mm"):
                row[f"{cam}_{kind}_png"] = f"{task['recording']}/{d}/{kind}/{name}"
        row["calibration"] = task["calibration_source"]
        row["calibration_sha256"] = task["calibration_sha256"]
        row["rig_hash"] = task["rig_hash"]
        rows.append(row)
    return rows


# ----------------------------------------------------------------------------- the export
def _fingerprint(manifest: dict) -> str:
    keep = {k: manifest[k] for k in ("format", "recordings", "params", "calibration", "rig_hash")}
    return hashlib.sha256(json.dumps(keep, sort_keys=True, default=str).encode()).hexdigest()


def _differences(old: dict, new: dict) -> list[str]:
    diffs = []
    if [r.get("fingerprint") for r in old.get("recordings", [])] != [r["fingerprint"] for r in new["recordings"]]:
        diffs.append("recordings " + ", ".join(r.get("path", "?") for r in old.get("recordings", [])))
    for k, v in new["params"].items():
        if old.get("params", {}).get(k) != v:
            diffs.append(f"{k} {old.get('params', {}).get(k)}")
    if old.get("calibration", {}).get("sha256") != new["calibration"]["sha256"]:
        diffs.append(f"calibration {old.get('calibration', {}).get('source')}")
    if old.get("rig_hash") != new["rig_hash"] and not diffs:
        diffs.append("rig description")
    return diffs or ["format"]


def _chunk_complete(out: Path, marker: Path) -> bool:
    """A chunk is done when its marker reads and every image it lists is still there."""
    try:
        rows = json.loads(marker.read_text())
    except (OSError, json.JSONDecodeError):
        return False
    return all((out / v).is_file() for r in rows for k, v in r.items() if k.endswith("_png"))


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
           on_chunk: Callable[[str], None] | None = None) -> dict:
    out = Path(out)
    try:
        cal = load_calibration(rig, calibration)
    except CalibrationError as exc:
        raise ExportError(str(exc)) from None
    recs, plans, tasks_by_rec, idents = [], [], [], []
    names = set()
    for path in recordings:
        try:
            rec = open_recording(path, rig, recover=recover)
            pl = plan(rec, rig, rate_hz=params.rate_hz, tolerance_ms=params.tolerance_ms,
                      ffc_margin=params.ffc_margin, keep_ffc=params.keep_ffc)
        except RecordingError as exc:
            raise ExportError(str(exc)) from None
        if rec.name in names:
            raise ExportError(f"{path}: two recordings named {rec.name!r}; give each a distinct folder name")
        names.add(rec.name)
        sizes = probe_sizes(rec)
        th_spec = rig.camera_model(rig.desc.sensors.thermal.camera_model)
        w, h = sizes["thermal_left"]
        rows = rig.desc.on_device.thermal_telemetry_rows
        # Boson telemetry rows below the image (platform_tools.boson.telemetry): not part of the picture
        th_h = h - rows if telemetry_rows_present(w, h, th_spec.width_px, th_spec.height_px, rows) else h
        if sizes["zed_depth"] != sizes["zed_left"]:
            raise ExportError(f"{rec.path}: the depth is {sizes['zed_depth'][0]}x{sizes['zed_depth'][1]}, the ZED "
                              f"left image {sizes['zed_left'][0]}x{sizes['zed_left'][1]}: depth_registered must "
                              f"be at the image's size")
        try:
            cams = {"zed_x_left_optical": cal.cams["zed_x_left_optical"].scaled(*sizes["zed_left"], str(rec.path)),
                    "thermal_left_optical": cal.cams["thermal_left_optical"].scaled(w, th_h, str(rec.path)),
                    "thermal_right_optical": cal.cams["thermal_right_optical"].scaled(
                        sizes["thermal_right"][0], th_h, str(rec.path))}
        except CalibrationError as exc:
            raise ExportError(str(exc)) from None
        recs.append(rec)
        plans.append(pl)
        idents.append(rec.identity() | {"offsets_ms": pl.offsets_ms, "clock_steps": pl.clock_steps,
                                        "counts": pl.counts})
        topics = {s: rec.streams[s].topic for s in IMAGE_STREAMS}
        chunks = []
        for c0 in range(0, len(pl.pairs), params.chunk_size):
            pairs = [asdict(p) for p in pl.pairs[c0:c0 + params.chunk_size]]
            chunks.append({"id": f"{rec.name}-{c0 // params.chunk_size:05d}", "recording": rec.name,
                           "files": [str(f.resolve()) for f in rec.files], "topics": topics, "pairs": pairs,
                           "cams": {n: {"lensmodel": c.lensmodel, "intrinsics": c.intrinsics.tolist(),
                                        "imagersize": list(c.imagersize), "rt_cam_ref": c.rt_cam_ref.tolist()}
                                    for n, c in cams.items()},
                           "thermal_height": th_h, "params": asdict(params), "out": str(out.resolve()),
                           "calibration_source": cal.source, "calibration_sha256": cal.sha256,
                           "rig_hash": rig.hash})
        tasks_by_rec.append(chunks)
    manifest = {"format": FORMAT, "recordings": [{k: v for k, v in i.items() if k != "clock_steps"} | {
        "clock_steps": i["clock_steps"]} for i in idents],
        "params": asdict(params), "calibration": {"source": cal.source, "sha256": cal.sha256},
        "rig_hash": rig.hash}
    manifest["fingerprint"] = _fingerprint(manifest)
    old = check_out(out, manifest)
    out.mkdir(parents=True, exist_ok=True)
    (out / CHUNKS).mkdir(exist_ok=True)
    tasks = [t for ch in tasks_by_rec for t in ch]
    done = {p.stem for p in (out / CHUNKS).glob("*.json") if _chunk_complete(out, p)}
    todo = [t for t in tasks if t["id"] not in done]
    manifest |= {"status": "running", "calibration_models": cal.to_dict(),
                 "chunks": len(tasks), "samples": sum(len(t["pairs"]) for t in tasks)}
    atomic.write_text(out / MANIFEST, json.dumps(manifest, indent=2) + "\n")
    resumed = old is not None and len(done) > 0
    if resumed:
        log.warning("%s: resuming: %d of %d chunks already done", out, len(tasks) - len(todo), len(tasks))

    def finished(task: dict, rows: list[dict]) -> None:
        atomic.write_text(out / CHUNKS / f"{task['id']}.json", json.dumps(rows) + "\n")
        if on_chunk:
            on_chunk(task["id"])

    run = {"inline": _run_inline, "pool": _run_pool, "dask": _run_dask}.get(engine)
    if run is None:
        raise ExportError(f"engine {engine!r}: expected inline, pool or dask")
    if todo:
        run(todo, finished, workers, scheduler)
    rows = []
    for t in tasks:
        rows += json.loads((out / CHUNKS / f"{t['id']}.json").read_text())
    write_index(out, rows)
    manifest |= {"status": "complete", "rows": len(rows)}
    atomic.write_text(out / MANIFEST, json.dumps(manifest, indent=2) + "\n")
    return {"out": str(out), "samples": len(rows), "chunks": len(tasks), "chunks_run": len(todo),
            "resumed": resumed, "engine": engine, "recordings": idents,
            "calibration": {"source": cal.source, "sha256": cal.sha256}}


def _bar(n: int):
    return progress(range(n), desc="export", total=n, unit="chunk")


def _run_inline(tasks, finished, workers, scheduler) -> None:
    bar = iter(_bar(len(tasks)))
    for t in tasks:
        finished(t, process_chunk(t))
        next(bar, None)


def _run_pool(tasks, finished, workers, scheduler) -> None:
    if workers <= 1:
        return _run_inline(tasks, finished, workers, scheduler)
    import multiprocessing
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
    bar = iter(_bar(len(tasks)))
    ctx = multiprocessing.get_context("spawn")     # no fork of a process holding numba / threads
    with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
        pending = {pool.submit(process_chunk, t): t for t in tasks}
        try:
            while pending:
                done, _ = wait(pending, return_when=FIRST_COMPLETED)
                for f in done:
                    t = pending.pop(f)
                    finished(t, f.result())
                    next(bar, None)
        except BaseException:
            for f in pending:
                f.cancel()
            raise


def _run_dask(tasks, finished, workers, scheduler) -> None:
    try:
        from distributed import Client, LocalCluster, as_completed
    except ImportError:
        raise ExportError("--engine dask needs dask.distributed (pip install 'dask[distributed]')") from None
    cluster = None
    if scheduler:
        client = Client(scheduler)
    else:
        cluster = LocalCluster(n_workers=max(1, workers), threads_per_worker=1, processes=True,
                               dashboard_address=None)
        client = Client(cluster)
    try:
        bar = iter(_bar(len(tasks)))
        futures = client.map(process_chunk, tasks, pure=False)
        by_key = {f.key: t for f, t in zip(futures, tasks)}
        for f in as_completed(futures):
            finished(by_key[f.key], f.result())
            next(bar, None)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


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
