"""A synthetic calibration set on disk: NNN.png (16-bit counts, or 8-bit AGC), truth.json and the truth
lens' files (truth.cameramodel for an mrcal lens; calibration/synth/truth_files.py for the others)."""
from __future__ import annotations

import io
import json
from pathlib import Path

import cv2
import numpy as np

from platform_tools.rig import atomic
from platform_tools.rig.cameras import imagersize
from platform_tools.rig.progress import progress

from .board import Board
from .difficulty import Difficulty, level
from .lens import as_cameramodel
from .poses import sample_view
from .agc import agc8
from .render import render_image
from .sensor import Sensor
from .truth_files import write_truth_files
from .truth_lens import RadialLens

OUTPUTS = ("y16", "agc8")     # 16-bit raw counts; 8-bit AGC (histogram equalised, as a Boson in 8-bit mode)


def default_lens(camera: str = "thermal_left", rig=None):
    """The nominal synthetic lens (an mrcal.cameramodel) of ``camera`` in the rig description."""
    from platform_tools.rig import load_rig

    from .lens import nominal_thermal_lens
    return nominal_thermal_lens(rig or load_rig(), camera)


def rt_from_R_t(R: np.ndarray, t: np.ndarray) -> list[float]:
    import mrcal
    return [float(x) for x in np.concatenate([mrcal.r_from_R(np.ascontiguousarray(R)), t])]


def render_dataset(out_dir, n: int = 40, difficulty: str | Difficulty = "real", board=(10, 7), square: float = 0.04,
                   seed: int = 0, lens=None, *, camera: str = "thermal_left", rig=None,
                   show_progress: bool = True, only=None, output: str = "y16") -> dict:
    """Render ``n`` images of a ``board`` (W, H inner corners, ``square`` metres) through ``lens``
    (an mrcal.cameramodel, a .cameramodel path or a (lensmodel, intrinsics, (W, H)) tuple; default: the
    nominal thermal lens of ``camera`` in the rig description) into ``out_dir``,
    replaced whole and atomically. ``difficulty``: a name (easy, real, hard) or a :class:`Difficulty`
    (e.g. one effect switched off, as bench/bench_corner_bias.py does). Returns the truth (also
    written to truth.json). ``only``: render just these image indices (each the same pixels as in
    the whole set: every image has its own random stream), e.g. one bench image for a test.
    ``lens`` may also be a truth lens of another family (a RadialLens: calibration/synth/truth_families.py).
    ``output``: "y16" (16-bit counts) or "agc8" (the same frames through the 8-bit AGC, calibration/synth/agc.py)."""
    if output not in OUTPUTS:
        raise ValueError(f"output={output!r}: one of {', '.join(OUTPUTS)}")
    diff = difficulty if isinstance(difficulty, Difficulty) else level(difficulty)
    difficulty = diff.name
    W, H = int(board[0]), int(board[1])
    if W < 2 or H < 2:
        raise ValueError(f"board {W}x{H}: needs at least 2x2 inner corners")
    if not (n >= 1):
        raise ValueError(f"n={n}: render at least one image")
    if not (square > 0):
        raise ValueError(f"square={square}: the square size must be positive (metres)")
    lens = as_cameramodel(lens) if lens is not None else default_lens(camera, rig)
    b = Board(W, H, float(square))
    rng = np.random.default_rng(seed)
    W_img, H_img = imagersize(lens)
    sensor = Sensor.make(rng, (H_img, W_img), diff)
    images = []
    out_dir = Path(out_dir)
    with atomic.OutputDir(out_dir) as stage:
        items = range(n) if only is None else sorted(int(k) for k in only if 0 <= int(k) < n)
        if show_progress:
            items = progress(items, desc=f"rendering {difficulty}", total=len(items), unit="image")
        for k in items:
            irng = np.random.default_rng([seed, k])
            view = sample_view(irng, lens, b, diff)
            img, occluded, look = render_image(irng, lens, b, view, diff, sensor)
            if output == "agc8":
                img = agc8(img)
            name = f"{k:03d}.png"
            ok, png = cv2.imencode(".png", img)
            if not ok:
                raise RuntimeError(f"cannot encode {name}")
            (stage / name).write_bytes(png.tobytes())
            corners = [None if not np.isfinite(q[0]) else [float(q[0]), float(q[1])] for q in view.corners_px]
            images.append({"file": name, "rt_cam_board": rt_from_R_t(view.R, view.t), "corners": corners,
                           "visible": view.visible, "occluded": [int(i) for i in np.flatnonzero(occluded)],
                           "polarity": "cooled" if look.polarity < 0 else "heated",
                           "contrast_k": round(look.contrast_k, 3)})
        lensmodel, intrinsics = lens.intrinsics()
        truth = {"lensmodel": lensmodel, "intrinsics": intrinsics.tolist(), "imagersize": [W_img, H_img],
                 "board": {"width": W, "height": H, "square_m": float(square)},
                 "difficulty": difficulty, "seed": seed, "images": images}
        if output != "y16":
            truth["output"] = output
        note = f"the exact lens the synthetic {difficulty} images (seed {seed}) were rendered through"
        if isinstance(lens, RadialLens):
            truth["truth_lens"] = {"family": lens.family, "name": lens.name,
                                   "files": write_truth_files(stage, lens, note)}
        else:
            buf = io.StringIO()
            lens.write(buf, note=note)
            (stage / "truth.cameramodel").write_text(buf.getvalue())
        (stage / "truth.json").write_text(json.dumps(truth, indent=1))
    return truth
