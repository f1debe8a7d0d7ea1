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

from . import thermal8
from .calib import FRAME_OF, model_from_dict, rt_a_b
from .decode import IMAGE_STREAMS, iter_frames
from .pairing import THERMAL
from .recording import RecordingError

_registrars: dict = {}


def _registrar(task: dict, side: str):
    from .register import Registrar
    key = (task["calibration_sha256"], side, json.dumps(task["cams"], sort_keys=True))
    if key not in _registrars:
        cams = {n: model_from_dict(c) for n, c in task["cams"].items()}
        frame = FRAME_OF[side]
        _registrars[key] = Registrar(cams["zed_x_left_optical"], cams[frame],
                                     rt_a_b(cams, frame, "zed_x_left_optical"),
                                     task["params"]["zbuffer_tolerance_percent"], task["params"]["min_coverage"])
    return _registrars[key]


_stereo: dict = {}


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
    return compute(task["depth"], got["zed_left"], got["zed_right"], _stereo[key])


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
    for (pi, s), _, img in iter_frames(files, wanted, lo, hi):
        images.setdefault(pi, {})[s] = img
    rows = []
    thermal_h = task["thermal_height"]
    for pi, pair in enumerate(task["pairs"]):
        got = images.get(pi, {})
        missing = [s for s in pair["frames"] if s not in got]
        if missing:
            raise RecordingError(f"{task['recording']} sample {pair['sample']}: {', '.join(missing)} not found in "
                              f"the MCAP (changed since it was indexed?)")
        name = f"{pair['sample']:06d}.png"
        row = {"recording": task["recording"], "sample": pair["sample"]}
        for s in IMAGE_STREAMS:
            if s in pair["frames"]:
                row[f"t_{s}_ns"] = pair["frames"][s]["stamp_ns"]
        for s, r in pair["residual_ms"].items():
            row[f"residual_{s}_ms"] = round(r, 4)
        zed = got["zed_left"]
        _write_png(rec_dir / "zed_left" / name, zed)
        _write_png(rec_dir / "zed_right" / name, got["zed_right"])
        row["zed_left_png"] = f"{task['recording']}/zed_left/{name}"
        row["zed_right_png"] = f"{task['recording']}/zed_right/{name}"
        depth = _depth(task, got)
        row["depth_source"] = task["depth"]
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
