"""One unit of the export's work: decode a chunk of paired samples from the MCAP, convert the thermal images
to 8-bit, register the ZED RGB into each thermal view, write the PNGs and return the chunk's index rows.

:func:`process_chunk` takes one task (a plain, picklable dict that export builds) so that every engine
(platform_tools.dataset.engines) runs the same function, in this process or another.
"""
from __future__ import annotations

import json
import os
from pathlib import Path

import cv2
import numpy as np

from . import encode, thermal8
from .calib import FRAME_OF, model_from_dict, rt_a_b
from .decode import IMAGE_STREAMS, Encoded, iter_frames
from .recording import THERMAL, RecordingError
from .workers import keep_freed_memory

_registrars: dict = {}
_rays: dict = {}


def _registrar(task: dict, side: str):
    """The registration into one thermal view, made once per calibration in this process; the ZED's ray grid
    (an mrcal unprojection of every pixel) once for both views."""
    from .register import Registrar, zed_rays
    key = (task["calibration_sha256"], side, json.dumps(task["cams"], sort_keys=True))
    if key not in _registrars:
        cams = {n: model_from_dict(c) for n, c in task["cams"].items()}
        frame = FRAME_OF[side]
        zed_key = json.dumps(task["cams"]["zed_x_left_optical"], sort_keys=True)
        if zed_key not in _rays:
            _rays[zed_key] = zed_rays(cams["zed_x_left_optical"])
        _registrars[key] = Registrar(cams["zed_x_left_optical"], cams[frame],
                                     rt_a_b(cams, frame, "zed_x_left_optical"),
                                     task["params"]["zbuffer_tolerance_percent"], task["params"]["min_coverage"],
                                     rays=_rays[zed_key])
    return _registrars[key]


_stereo: dict = {}


def _pixels(got: dict, stream: str) -> np.ndarray:
    """The image of ``stream`` in one sample's ``got`` (stream -> image or decode.Encoded), decoded once."""
    img = got[stream]
    if isinstance(img, Encoded):
        img = got[stream] = img.image()
    return img


def _depth(task: dict, got: dict) -> np.ndarray:
    """The ZED left depth of one sample: recorded, or computed from the stereo pair (stereo.py)."""
    if task["depth"] == "recorded":
        return got["zed_depth"]
    from .stereo import StereoCalibration, compute
    key = json.dumps([task["cams"]["zed_x_left_optical"], task["cams"]["zed_x_right_optical"]], sort_keys=True)
    if key not in _stereo:
        _stereo[key] = StereoCalibration(model_from_dict(task["cams"]["zed_x_left_optical"]),
                                         model_from_dict(task["cams"]["zed_x_right_optical"]),
                                         f"{task['recording']}: the ZED pair")
    return compute(task["depth"], _pixels(got, "zed_left"), _pixels(got, "zed_right"), _stereo[key])


#: every image kind an export can write (Params.outputs chooses among them)
KINDS = ("zed_left", "zed_right", "raw16", "8bit", "rgb_registered", "mask", "depth_mm")
#: the kinds written per thermal camera, in <recording>/<camera>/<kind>/ with index column <camera>_<kind>_png
THERMAL_KINDS = ("raw16", "8bit", "rgb_registered", "mask", "depth_mm")
#: processing.zed_images: "as_recorded" writes a compressed ZED topic's image file (JPEG, or PNG) as the recording
#: holds it, byte for byte, in <recording>/zed_left/NNNNNN.jpg with index column zed_left_jpg (a raw topic: PNG,
#: zed_left_png); "png" decodes every ZED image and writes it as PNG (column zed_left_png)
ZED_IMAGES = ("as_recorded", "png")
#: how the index's columns that name a written file end
FILE_COLUMNS = ("_png", "_jpg")
#: a writer's temporary file: ``.<name>.<pid>.tmp`` beside the image it becomes (engines remove a stopped
#: worker's by its pid; a resumed export removes any left by a killed one)
TMP_SUFFIX = ".tmp"


def png_bytes(img: np.ndarray, level: int | None) -> bytes:
    """The PNG file of one image: ``level`` None (processing.png_compression_level's default) is this package's fast
    writer (encode.png: ISA-L deflate level 1, UP filter; 2.5 to 4 times faster than OpenCV's libpng, docs/dataset.md);
    0..9 is OpenCV's libpng at that zlib level, for whoever wants smaller files at a higher CPU cost. The pixels
    are the same whichever is chosen."""
    if level is None:
        return encode.png(img)
    ok, buf = cv2.imencode(".png", img, [cv2.IMWRITE_PNG_COMPRESSION, int(level)])
    if not ok:
        raise encode.EncodeError(f"OpenCV could not encode a {img.dtype} image of shape {img.shape} as PNG")
    return buf.tobytes()


def tmp_name(path: Path, pid: int) -> Path:
    return path.with_name(f".{path.name}.{pid}{TMP_SUFFIX}")


def _write_png(path: Path, img: np.ndarray, level: int | None) -> None:
    try:
        data = png_bytes(img, level)
    except encode.EncodeError as exc:
        raise OSError(f"{path}: {exc}") from None
    _write_file(path, data)


def _write_file(path: Path, data: bytes) -> None:
    """``data`` in the file ``path``, whole or not at all (a temporary file renamed)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = tmp_name(path, os.getpid())
    try:
        tmp.write_bytes(data)
        os.replace(tmp, path)
    except BaseException:           # an interrupt or a full disk: no half-written file left behind
        tmp.unlink(missing_ok=True)
        raise


def _read(task: dict) -> dict[int, dict[str, np.ndarray | Encoded]]:
    """The decoded images of the chunk's samples: sample position -> stream -> image, or the decode.Encoded file
    of a compressed ZED image written as recorded (ZED_IMAGES). Only the MCAP chunks around each sample's messages
    are read, each once (decode.windows)."""
    wanted, logs = {}, []
    for pi, pair in enumerate(task["pairs"]):
        for s, fr in pair["frames"].items():
            wanted[(task["topics"][s], fr["stamp_ns"])] = (pi, s)
            logs.append(fr["log_ns"])
    files = sorted({task["files"][fr["file"]] for p in task["pairs"] for fr in p["frames"].values()})
    as_recorded = task["params"]["zed_images"] == "as_recorded"      # Params.zed_images, always in a task
    keep = frozenset(task["topics"][s] for s in ("zed_left", "zed_right") if as_recorded and s in task["topics"])
    images: dict[int, dict[str, np.ndarray | Encoded]] = {}
    for (pi, s), _, img in iter_frames(files, wanted, logs, keep_encoded=keep):
        images.setdefault(pi, {})[s] = img
    return images


def preload() -> None:
    """What the index's scans need (indexscan.scan_part): the MCAP reader imported, in the process a pool's workers
    are forked from (engines.Pool ``preload``)."""
    import mcap.reader  # noqa: F401
    import mcap_ros2.decoder  # noqa: F401


def warm_up() -> None:
    """Make this process ready for :func:`process_chunk` before its first task (engines.Pool runs it in each worker:
    a spawned one as it starts, a forked one after the index): the kernels of the 8-bit conversion and the
    registration loaded (:mod:`.kernels`: the extension built ahead of time, without numba; else numba's, its
    registries loaded without scipy.linalg), mrcal and the MCAP reader imported. No OpenCV call (a thread pool OpenCV
    started would not survive a fork)."""
    preload()
    from . import register
    thermal8.warm_up()
    register.warm_up()


def process_chunk(task: dict) -> list[dict]:
    """Decode, convert, register and write one chunk of samples; return their index rows."""
    cv2.setNumThreads(1)
    keep_freed_memory()
    out = Path(task["out"])
    rec = task["recording"]
    rec_dir = out / rec
    params = task["params"]
    p8 = thermal8.Params(**params["thermal_8bit"])
    kinds = set(params.get("outputs") or KINDS)
    png = params.get("png_compression_level")
    images = _read(task)
    rows = []
    thermal_h = task["thermal_height"]
    for pi, pair in enumerate(task["pairs"]):
        got = images.get(pi, {})
        missing = [s for s in pair["frames"] if s not in got]
        if missing:
            raise RecordingError(f"{rec} sample {pair['sample']}: {', '.join(missing)} not found in "
                                 f"the MCAP (changed since it was indexed?)")
        name = f"{pair['sample']:06d}.png"
        row = {"recording": rec, "sample": pair["sample"]}
        for s in IMAGE_STREAMS:
            if s in pair["frames"]:
                row[f"t_{s}_ns"] = pair["frames"][s]["stamp_ns"]
        for s, r in pair["residual_ms"].items():
            row[f"residual_{s}_ms"] = round(r, 4)
        for s in ("zed_left", "zed_right"):
            if s in kinds:
                img = got[s]
                if isinstance(img, Encoded):
                    file = f"{pair['sample']:06d}{img.suffix}"
                    _write_file(rec_dir / s / file, img.data)
                else:
                    file = name
                    _write_png(rec_dir / s / name, img, png)
                row[f"{s}_{Path(file).suffix[1:]}"] = f"{rec}/{s}/{file}"
        zed = _pixels(got, "zed_left")
        depth = _depth(task, got)
        row["depth_source"] = task["depth"]
        for cam in THERMAL:
            raw = got[cam]
            if raw.shape[0] > thermal_h:          # Boson telemetry rows appended below the image
                raw = raw[:thermal_h]
            img8, info = thermal8.to_8bit(raw, p8)
            reg = _registrar(task, cam).register_u8(depth, zed)
            made = {"raw16": lambda: raw.astype(np.uint16, copy=False), "8bit": lambda: img8,
                    "rgb_registered": lambda: reg.image, "mask": lambda: reg.mask, "depth_mm": lambda: reg.depth_mm}
            row |= {f"{cam}_ffc": pair["ffc"][cam], f"{cam}_ffc_status": pair["ffc_status"][cam],
                    f"{cam}_since_ffc_s": pair["since_ffc_s"][cam],
                    f"{cam}_lo_counts": info["lo_counts"], f"{cam}_hi_counts": info["hi_counts"],
                    f"{cam}_percentile_clip": info["percentile_clip"],
                    f"{cam}_registered_fraction": round(reg.fraction, 4)}
            for kind in THERMAL_KINDS:
                if kind in kinds:
                    _write_png(rec_dir / cam / kind / name, made[kind](), png)
                    row[f"{cam}_{kind}_png"] = f"{rec}/{cam}/{kind}/{name}"
        row["calibration"] = task["calibration_source"]
        row["calibration_sha256"] = task["calibration_sha256"]
        row["rig_hash"] = task["rig_hash"]
        rows.append(row)
    return rows
