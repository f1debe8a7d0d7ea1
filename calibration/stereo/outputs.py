"""What ``calibrate thermal-stereo`` writes, as bytes per file name, each read back before it is kept:

- ``left.cameramodel``, ``right.cameramodel``: the solved pair (reference: the left optical frame; the
  right's ``extrinsics_rt_fromref`` is rt_right_left), with mrcal's optimization_inputs;
- ``rectified_left.cameramodel``, ``rectified_right.cameramodel``: mrcal's rectified system (LATLON);
- ``rectification_left.npy``, ``rectification_right.npy``: float32 (Hr, Wr, 2) maps for
  ``cv2.remap(image, np.load(f), None, cv2.INTER_LINEAR)``;
- ``stereo.json``: the report (pose, difference from the seed, RMS, epipolar error).
"""
from __future__ import annotations

import io
import json

import numpy as np

MODEL_FILES = ("left.cameramodel", "right.cameramodel")
RECTIFIED_FILES = ("rectified_left.cameramodel", "rectified_right.cameramodel")
MAP_FILES = ("rectification_left.npy", "rectification_right.npy")
REPORT = "stereo.json"
READBACK_RTOL = 1e-9


class ReadbackError(Exception):
    """A written file does not read back as what was meant (a defect, not bad input)."""


def model_bytes(model, note: str) -> bytes:
    buf = io.StringIO()
    model.write(buf, note=note)
    return buf.getvalue().encode()


def map_bytes(m: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.save(buf, np.ascontiguousarray(m, dtype=np.float32), allow_pickle=False)
    return buf.getvalue()


def read_model(data: bytes):
    """An mrcal.cameramodel parsed from a file's bytes, as mrcal reads the file."""
    import mrcal
    return mrcal.cameramodel(io.StringIO(data.decode()))


def check_model(name: str, data: bytes, model) -> None:
    """Raise ReadbackError unless ``data`` reads back as ``model``'s lens, imager and extrinsics (mrcal
    writes 10 significant digits: equal to 1e-9 relative, 1e-12 absolute)."""
    back = read_model(data)
    lm, intr = model.intrinsics()
    close = lambda a, b: np.allclose(a, b, rtol=READBACK_RTOL, atol=1e-12)
    if back.intrinsics()[0] != lm or not close(back.intrinsics()[1], intr) or \
            not np.array_equal(back.imagersize(), model.imagersize()) or \
            not close(back.extrinsics_rt_fromref(), model.extrinsics_rt_fromref()):
        raise ReadbackError(f"{name}: does not read back as the model written")


def all_files(models, rectified, maps, report: dict, *, seed_note: str) -> dict[str, bytes]:
    """Every output file's bytes (see the module docstring), each checked by reading it back."""
    files: dict[str, bytes] = {}
    for name, m, side in zip(MODEL_FILES, models, ("left", "right")):
        files[name] = model_bytes(m, f"thermal {side} camera of the stereo pair (calibrate thermal-stereo; "
                                     f"reference frame: the left optical frame; {seed_note})")
    for name, m, side in zip(RECTIFIED_FILES, rectified, ("left", "right")):
        files[name] = model_bytes(m, f"rectified {side} view of the thermal stereo pair (mrcal.rectified_system)")
    for name, m in zip(MAP_FILES, maps):
        files[name] = map_bytes(m)
    for name, m in zip(MODEL_FILES + RECTIFIED_FILES, tuple(models) + tuple(rectified)):
        check_model(name, files[name], m)
    for name, m in zip(MAP_FILES, maps):
        back = np.load(io.BytesIO(files[name]), allow_pickle=False)
        if back.dtype != np.float32 or back.shape != m.shape or not np.array_equal(back, m, equal_nan=True):
            raise ReadbackError(f"{name}: does not read back as the map written")
    files[REPORT] = (json.dumps(report, indent=1) + "\n").encode()
    return files
