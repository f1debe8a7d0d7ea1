"""Render one thermal image of the board: every output pixel is split into SS x SS sub-pixels, each
sub-pixel's ray (the lens' exact unprojection) is intersected with the board plane, and the board
signal is evaluated there. The true corner position is the exact projection of the corner point, so
the truth is exact whatever the lens; supersampling makes the rendered edges match it (tests measure
the residual bias with the detector on noise-free images)."""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from platform_tools.rig.cameras import camera_model, imagersize

from .board import Board
from .difficulty import Difficulty
from .lens import unproject
from .truth_lens import RadialLens
from .poses import BoardView
from .scene import AMBIENT_K, background, hand
from .sensor import Sensor

SUPERSAMPLE = 4


def ray_grid(lens, ss: int = SUPERSAMPLE) -> np.ndarray:
    """Unit rays (H*ss, W*ss, 3) float32 of every sub-pixel centre of ``lens`` (an mrcal.cameramodel);
    pixel (x, y) spans x +- 0.5. Cached by the lens' values (a set's images share one grid)."""
    if isinstance(lens, RadialLens):
        return _truth_ray_grid(lens, ss)
    lm, intr = lens.intrinsics()
    return _ray_grid(lm, tuple(float(x) for x in intr), imagersize(lens), ss)


@lru_cache(maxsize=2)
def _ray_grid(lensmodel: str, intrinsics: tuple[float, ...], size: tuple[int, int], ss: int) -> np.ndarray:
    return _sub_pixel_rays(camera_model(lensmodel, intrinsics, size), size, ss)


@lru_cache(maxsize=2)
def _truth_ray_grid(lens: RadialLens, ss: int) -> np.ndarray:
    return _sub_pixel_rays(lens, lens.size, ss)


def _sub_pixel_rays(lens, size: tuple[int, int], ss: int) -> np.ndarray:
    W, H = size
    off = (np.arange(ss) + 0.5) / ss - 0.5
    xs = (np.arange(W)[:, None] + off[None, :]).ravel()
    ys = (np.arange(H)[:, None] + off[None, :]).ravel()
    q = np.empty((len(ys), len(xs), 2))
    q[..., 0] = xs[None, :]
    q[..., 1] = ys[:, None]
    return unproject(q, lens).astype(np.float32)


@dataclass(frozen=True)
class Look:
    """Per-image draws of the appearance."""
    contrast_k: float
    spread_m: float
    polarity: float            # +1 heated board, -1 cooled board
    board_offset_k: float      # board mean minus ambient
    blur_px: float
    reflection: tuple[float, float, float, float] | None   # (u, v, sigma_m, strength) on the board
    occluded: bool

    @staticmethod
    def draw(rng: np.random.Generator, diff: Difficulty, board: Board) -> "Look":
        pol = -1.0 if rng.random() < diff.inverted_prob else 1.0
        contrast = rng.uniform(*diff.contrast_k)
        refl = None
        if rng.random() < diff.reflection_prob:
            u0, u1, v0, v1 = board.extent()
            refl = (rng.uniform(u0, u1), rng.uniform(v0, v1), rng.uniform(0.05, 0.15),
                    rng.uniform(*diff.reflection_strength))
        return Look(contrast, rng.uniform(*diff.heat_spread_mm) / 1000.0, pol,
                    pol * (contrast / 2 + rng.uniform(0.5, 3.0)), rng.uniform(*diff.blur_px), refl,
                    rng.random() < diff.occluder_prob)


def board_layer(lens, board: Board, view: BoardView, look: Look, diff: Difficulty,
                ss: int = SUPERSAMPLE) -> tuple[np.ndarray, np.ndarray]:
    """(coverage, board temperature) per pixel: the area share of the pixel the board covers and the
    mean board temperature over that share (kelvin; ambient where coverage is 0)."""
    W, H = imagersize(lens)
    rays = ray_grid(lens, ss)
    R = view.R.astype(np.float32)
    t = view.t.astype(np.float32)
    n = R[:, 2]
    denom = rays @ n
    lam = float(n @ t) / np.where(denom > 1e-6, denom, np.inf).astype(np.float32)
    # board coordinates of the hit point: R^T (lam v - t)
    u = lam * (rays @ R[:, 0]) - float(R[:, 0] @ t)
    v = lam * (rays @ R[:, 1]) - float(R[:, 1] @ t)
    inside = (denom > 1e-6) & board.inside(u, v)
    ui, vi = u[inside].astype(np.float64), v[inside].astype(np.float64)
    sig = board.pattern(ui, vi, look.spread_m)
    # contrast: heater falloff at the rim, a warm reflection, and emissivity falling at grazing angles
    c = board.centre()
    u0, u1, v0, v1 = board.extent()
    rim = ((ui - c[0]) / ((u1 - u0) / 2)) ** 2 + ((vi - c[1]) / ((v1 - v0) / 2)) ** 2
    gain = 1.0 - diff.board_gradient * np.clip(rim, 0, 2) / 2
    if look.reflection is not None:
        ru, rv, rs, strength = look.reflection
        gain = gain * (1.0 - strength * np.exp(-((ui - ru) ** 2 + (vi - rv) ** 2) / (2 * rs * rs)))
    gain = gain * np.abs(denom[inside]) ** 0.3
    temp = np.full(inside.shape, 0.0, np.float32)
    temp[inside] = (look.board_offset_k + look.polarity * look.contrast_k / 2 * gain * sig).astype(np.float32)
    cov = inside.reshape(H, ss, W, ss).mean(axis=(1, 3), dtype=np.float32)
    tsum = temp.reshape(H, ss, W, ss).sum(axis=(1, 3), dtype=np.float32)
    mean = np.where(cov > 0, tsum / np.maximum(cov * ss * ss, 1e-9), 0.0).astype(np.float32)
    return cov, AMBIENT_K + mean


def render_image(rng: np.random.Generator, lens, board: Board, view: BoardView, diff: Difficulty,
                 sensor: Sensor) -> tuple[np.ndarray, np.ndarray, Look]:
    """One uint16 frame and the per-corner occlusion flags (True where a hand covers the corner)."""
    W, H = imagersize(lens)
    look = Look.draw(rng, diff, board)
    bg = background(rng, (H, W), diff.clutter)
    cov, board_k = board_layer(lens, board, view, look, diff)
    scene = (1 - cov) * bg + cov * board_k
    occluded = np.zeros(board.n, bool)
    if look.occluded:
        seen = np.flatnonzero(np.isfinite(view.corners_px[:, 0]))
        rim = [k for k in seen if k // board.width in (0, board.height - 1) or k % board.width in (0, board.width - 1)]
        anchor = view.corners_px[rng.choice(rim) if rim else rng.choice(seen)]
        hcov, hand_k = hand(rng, (H, W), anchor)
        scene = (1 - hcov) * scene + hcov * hand_k
        q = view.corners_px
        fin = np.isfinite(q[:, 0])
        xi = np.clip(np.rint(np.nan_to_num(q[:, 0])).astype(int), 0, W - 1)
        yi = np.clip(np.rint(np.nan_to_num(q[:, 1])).astype(int), 0, H - 1)
        # a corner counts as occluded when the hand covers any of the 5x5 pixels around it
        import cv2
        near = cv2.dilate((hcov > 0).astype(np.uint8), np.ones((5, 5), np.uint8)) > 0
        occluded = fin & near[yi, xi]
    return sensor.expose(rng, scene, look.blur_px), occluded, look


def view_angle_deg(view: BoardView) -> float:
    """Tilt of the board against the line of sight to its centre."""
    c = view.t + view.R @ np.zeros(3)
    return math.degrees(math.acos(abs(float(view.R[:, 2] @ c / np.linalg.norm(c)))))
