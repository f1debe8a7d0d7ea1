"""Render the same board poses through every camera of the rig.

- Truth: each camera's optical frame is its CAD pose moved by a random rigid offset in its own
  frame (``perturb_mm`` and ``perturb_deg`` in magnitude, each times 0.75-1.25, random directions).
- Thermal cameras: the thermal renderer as it is (calibration.synth: heated board, microbolometer,
  16-bit counts), through the nominal Boson lens (OPENCV8) with a small per-camera change of focal
  length (+-0.5 %) and principal point (+-3 px), so the two thermal lenses differ.
- RGB cameras: an 8-bit, 3-channel image of a printed board (white/black, high contrast, a smooth
  coloured background, a little blur and noise) through the ZED's nominal lens: a pinhole with
  f = focal length / pixel pitch and the principal point at the centre (the ZED publishes rectified
  images, for which a pinhole is exact). ``rgb_scale`` renders at a reduced size for speed: the
  imager is round(W s) x round(H s) and the intrinsics are scaled to it by the project's one resize rule
  (``platform_tools.rig.cameras.scaled``), so the truth is exactly the lens of the rendered images.
- Board poses are drawn in the rig frame, 0.8 to 2.2 m ahead, facing the rig (tilted up to 35 deg,
  rolled +-10 deg: upright, so every camera sees the same top-left corner); a pose is kept only when
  every corner is inside every camera's image with a margin and squares are at least 8 px.

Layout: ``DIR/<camera>/<timestamp_ns>.png`` (camera: zed_left, zed_right, thermal_left, thermal_right),
ZED left and right with the same stamp, thermal stamps 1-2 ms later (within the rig's pair tolerance);
``DIR/truth.json`` and ``DIR/truth/<camera>.cameramodel`` (the true lens and true extrinsics,
rt_fromref = rig frame -> optical frame, metres).
"""
from __future__ import annotations

import dataclasses
import io
import json
import math
from pathlib import Path

import cv2
import numpy as np

from platform_tools.rig import atomic
from platform_tools.rig.cameras import camera_model, imagersize, scaled
from platform_tools.rig.frames import Pose, rotvec_to_matrix
from platform_tools.rig.nominal import nominal_camera
from platform_tools.rig.progress import progress

from ..extrinsics.cad import CAMERAS, FrameTree, cad_frames
from ..extrinsics.outputs import pose_dict
from ..synth import Board, nominal_thermal_lens
from ..synth.lens import project
from ..synth.difficulty import level
from ..synth.poses import BoardView
from ..synth.render import Look, board_layer, render_image
from ..synth.scene import AMBIENT_K, smooth_field
from ..synth.sensor import Sensor

CAMERA_FOLDERS = tuple(CAMERAS)
THERMAL = ("thermal_left", "thermal_right")
RGB = ("zed_left", "zed_right")
MARGIN_PX = 8.0
MIN_SQUARE_PX = 8.0
RGB_SUPERSAMPLE = 2
T0_NS = 1_700_000_000_000_000_000


def zed_lens(rig, scale: float = 1.0):
    """The ZED's nominal pinhole (an mrcal.cameramodel) for images of round(W s) x round(H s) px
    (``platform_tools.rig.cameras.scaled``: the one resize rule)."""
    nominal = nominal_camera(rig, CAMERAS["zed_left"])
    W, H = imagersize(nominal)
    return scaled(nominal, (int(round(W * scale)), int(round(H * scale))), what=f"rgb_scale={scale}")


def true_lenses(rig, rng: np.random.Generator, rgb_scale: float) -> dict:
    """camera short name -> its true lens (an mrcal.cameramodel, identity pose): the ZED's nominal
    pinhole at ``rgb_scale``, and each thermal camera's nominal lens with its focal length and principal
    point moved a little (see the module docstring)."""
    out = {}
    z = zed_lens(rig, rgb_scale)
    out["zed_left"] = out["zed_right"] = z
    for short in THERMAL:
        base = nominal_thermal_lens(rig, short)
        lensmodel, intr = base.intrinsics()
        k = 1.0 + rng.uniform(-0.005, 0.005)
        intr[0] *= k
        intr[1] *= k
        intr[2] += rng.uniform(-3, 3)
        intr[3] += rng.uniform(-3, 3)
        out[short] = camera_model(lensmodel, intr, imagersize(base))
    return out


def perturbed(tree: FrameTree, rng: np.random.Generator, mm: float, deg: float) -> dict[str, Pose]:
    """The true optical frames: CAD moved by a random offset in each camera's own frame."""
    out = {}
    for short, frame in CAMERAS.items():
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        angle = math.radians(deg) * rng.uniform(0.75, 1.25)
        d = rng.normal(size=3)
        d *= mm * rng.uniform(0.75, 1.25) / np.linalg.norm(d)
        out[short] = tree.T_rig[frame] @ Pose(rotvec_to_matrix(axis * angle), d)
    return out


def _project(lens, board: Board, T_cam_board: Pose) -> np.ndarray:
    p = T_cam_board.apply(board.corners() * 1000.0) / 1000.0
    if np.any(p[:, 2] <= 0.1):
        return np.full((board.n, 2), np.nan)
    return project(p, lens)


def _board_ok(q: np.ndarray, lens, board: Board) -> bool:
    W, H = imagersize(lens)
    if not np.all(np.isfinite(q)):
        return False
    if np.any((q[:, 0] < MARGIN_PX) | (q[:, 0] > W - 1 - MARGIN_PX) | (q[:, 1] < MARGIN_PX) |
              (q[:, 1] > H - 1 - MARGIN_PX)):
        return False
    g = q.reshape(board.height, board.width, 2)
    d = np.concatenate([np.linalg.norm(np.diff(g, axis=1), axis=2).ravel(),
                        np.linalg.norm(np.diff(g, axis=0), axis=2).ravel()])
    return bool(d.min() >= MIN_SQUARE_PX)


def sample_board_pose(rng: np.random.Generator, true_T: dict[str, Pose], lenses: dict, board: Board,
                      max_tries: int = 2000) -> tuple[Pose, dict[str, np.ndarray]]:
    """A board pose in the rig frame (mm) seen whole by every camera, and its true corners per camera."""
    ref = true_T["thermal_left"]          # the narrowest view: aim the board through it
    centre_mm = board.centre() * 1000.0
    for _ in range(max_tries):
        dist = rng.uniform(800.0, 2200.0)
        ang = np.radians(rng.uniform(-30, 30)), np.radians(rng.uniform(-22, 22))
        v = np.array([math.tan(ang[0]), math.tan(ang[1]), 1.0])
        v /= np.linalg.norm(v)
        z = v                                              # board normal along the line of sight
        x = np.array([1.0, 0.0, 0.0]) - z[0] * z
        x /= np.linalg.norm(x)
        R = np.stack([x, np.cross(z, x), z], axis=1)
        phi = rng.uniform(0, 2 * math.pi)
        tilt = math.radians(35.0) * math.sqrt(rng.uniform(0, 1))
        axis = R[:, 0] * math.cos(phi) + R[:, 1] * math.sin(phi)
        roll = math.radians(rng.uniform(-10, 10))
        R = rotvec_to_matrix(axis * tilt) @ R @ rotvec_to_matrix(np.array([0.0, 0.0, roll]))
        T_ref_board = Pose(R, dist * v - R @ centre_mm)
        T_rig_board = ref @ T_ref_board
        corners = {}
        for short, lens in lenses.items():
            q = _project(lens, board, true_T[short].inverse() @ T_rig_board)
            if not _board_ok(q, lens, board):
                break
            corners[short] = q
        else:
            return T_rig_board, corners
    raise RuntimeError(f"no board pose is seen whole by every camera in {max_tries} tries; use a smaller board")


def _view(board: Board, lens, T_cam_board: Pose, corners: np.ndarray) -> BoardView:
    return BoardView(T_cam_board.R, T_cam_board.t / 1000.0, corners, False)


def render_rgb(rng: np.random.Generator, lens, board: Board, view: BoardView) -> np.ndarray:
    """An 8-bit BGR image of a printed board (white/black squares, grey border) under a tinted light."""
    W, H = imagersize(lens)
    diff = dataclasses.replace(level("easy"), board_gradient=0.0)
    look = Look(contrast_k=2.0, spread_m=0.0002, polarity=1.0, board_offset_k=0.0, blur_px=0.0,
                reflection=None, occluded=False)
    cov, board_k = board_layer(lens, board, view, look, diff, ss=RGB_SUPERSAMPLE)
    sig = np.clip(board_k - AMBIENT_K, -1.0, 1.0)           # the checker signal, shaded by the angle
    refl = 0.5 + 0.4 * sig
    light = rng.uniform(0.8, 1.0) * np.array([rng.uniform(0.9, 1.0), 1.0, rng.uniform(0.85, 1.0)])
    bg = np.stack([0.45 + smooth_field(rng, (H, W), (5, 6), 0.12) for _ in range(3)], axis=-1)
    img = (cov[..., None] * refl[..., None] + (1 - cov[..., None]) * bg) * light[None, None, :]
    img = cv2.GaussianBlur(img.astype(np.float32), (0, 0), 0.6)
    img += rng.normal(0.0, 0.01, size=img.shape).astype(np.float32)
    return np.clip(np.rint(255.0 * np.clip(img, 0, 1) ** (1 / 2.2)), 0, 255).astype(np.uint8)


def render_rig_dataset(out_dir, n: int = 30, *, board=(10, 7), square: float = 0.05, seed: int = 0, rig=None,
                       rgb_scale: float = 0.5, perturb_mm: float = 2.0, perturb_deg: float = 0.5,
                       difficulty: str = "easy", show_progress: bool = False) -> dict:
    """Render ``n`` synchronised sets into ``out_dir`` (replaced whole); returns the truth."""
    from platform_tools.rig import load_rig
    rig = rig or load_rig()
    if not 0.05 <= rgb_scale <= 1.0:
        raise ValueError(f"rgb_scale={rgb_scale}: between 0.05 and 1")
    b = Board(int(board[0]), int(board[1]), float(square))
    rng = np.random.default_rng(seed)
    tree = cad_frames(rig)
    lenses = true_lenses(rig, rng, rgb_scale)
    true_T = perturbed(tree, rng, perturb_mm, perturb_deg)
    diff = level(difficulty)
    sensors = {s: Sensor.make(rng, imagersize(lenses[s])[::-1], diff) for s in THERMAL}
    thermal_lag_ns = int(rng.uniform(1.0e6, 2.0e6))
    sets = []
    for k in range(n):
        srng = np.random.default_rng([seed, k])
        T_rig_board, corners = sample_board_pose(srng, true_T, lenses, b)
        stamp = T0_NS + k * 2_000_000_000 + int(srng.integers(0, 1_000_000))
        stamps = {s: stamp + (thermal_lag_ns + int(srng.integers(-200_000, 200_000)) if s in THERMAL else 0)
                  for s in CAMERA_FOLDERS}
        sets.append(dict(index=k, T_rig_board=T_rig_board, corners=corners, stamps=stamps))
    out_dir = Path(out_dir)
    with atomic.OutputDir(out_dir) as stage:
        # camera by camera: each lens' ray grid is computed once
        jobs = [(s, st) for s in CAMERA_FOLDERS for st in sets]
        if show_progress:
            jobs = progress(jobs, desc="rendering rig sets", total=len(jobs), unit="image")
        for s in CAMERA_FOLDERS:
            (stage / s).mkdir()
        for short, st in jobs:
            lens = lenses[short]
            T_cam_board = true_T[short].inverse() @ st["T_rig_board"]
            view = _view(b, lens, T_cam_board, st["corners"][short])
            irng = np.random.default_rng([seed, st["index"], CAMERA_FOLDERS.index(short)])
            if short in THERMAL:
                img, _, _ = render_image(irng, lens, b, view, diff, sensors[short])
            else:
                img = render_rgb(irng, lens, b, view)
            ok, png = cv2.imencode(".png", img)
            if not ok:
                raise RuntimeError(f"cannot encode {short}/{st['stamps'][short]}.png")
            (stage / short / f"{st['stamps'][short]}.png").write_bytes(png.tobytes())
        truth = {
            "convention": "T_rig_cam: the camera's optical frame in the rig frame (mm); rt_cam_rig_m: mrcal "
                          "rt_fromref (rig -> camera, metres); T_rig_board: the board frame (corner (i, j) at "
                          "(i s, j s, 0)) in the rig frame",
            "rgb_scale": rgb_scale, "seed": seed, "difficulty": difficulty,
            "board": {"width": b.width, "height": b.height, "square_m": b.square_m},
            "perturbation": {"mm": perturb_mm, "deg": perturb_deg}, "rig_hash": rig.hash,
            "cameras": {s: {"frame": CAMERAS[s], "lensmodel": lenses[s].intrinsics()[0],
                            "intrinsics": lenses[s].intrinsics()[1].tolist(),
                            "imagersize": list(imagersize(lenses[s])),
                            "T_rig_cam_true": pose_dict(true_T[s]), "T_rig_cam_cad": pose_dict(tree.camera(s)),
                            "rt_cam_rig_true_m": true_T[s].inverse().rt(metres=True).tolist(),
                            "rt_cam_rig_cad_m": tree.camera(s).inverse().rt(metres=True).tolist(),
                            "cad_to_true_mm": float(np.linalg.norm((tree.camera(s).inverse() @ true_T[s]).t)),
                            "cad_to_true_deg": (tree.camera(s).inverse() @ true_T[s]).angle_deg()}
                        for s in CAMERA_FOLDERS},
            "sets": [{"index": st["index"], "files": {s: f"{s}/{st['stamps'][s]}.png" for s in CAMERA_FOLDERS},
                      "stamps_ns": st["stamps"], "T_rig_board": pose_dict(st["T_rig_board"]),
                      "corners": {s: [[float(x), float(y)] for x, y in st["corners"][s]] for s in CAMERA_FOLDERS}}
                     for st in sets]}
        (stage / "truth.json").write_text(json.dumps(truth, indent=1))
        (stage / "truth").mkdir()
        for s in CAMERA_FOLDERS:
            m = camera_model(*lenses[s].intrinsics(), imagersize(lenses[s]), true_T[s].inverse().rt(metres=True))
            buf = io.StringIO()
            m.write(buf, note=f"true lens and extrinsics of {s} in the synthetic rig set (seed {seed})")
            (stage / "truth" / f"{s}.cameramodel").write_text(buf.getvalue())
    return truth
