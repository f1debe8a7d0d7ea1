"""Board poses a person holding a heated board in front of the thermal camera would produce.

The board faces the camera (its normal along the ray to where it appears), then tilts about a
random in-plane axis and rolls a little about its normal. Where it appears in the image and how big
it looks are drawn per difficulty; poses whose corners break the difficulty's rules (fully visible
when it must be, squares too small, corners behind the lens' valid field) are drawn again.

The roll stays within +-30 deg: the board is held upright, so the truth's corner (0, 0) is the
top-left corner as seen in the image, the convention the detector follows.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from platform_tools.rig.cameras import imagersize
from platform_tools.rig.frames import rotvec_to_matrix

from .board import Board
from .difficulty import Difficulty
from .lens import max_valid_angle_rad, project, unproject

FULL_MARGIN_PX = 6.0       # a "fully visible" board keeps every corner this far inside the image
MIN_PARTIAL_SHARE = 0.35   # a partial board keeps at least this share of its corners in view


@dataclass(frozen=True)
class BoardView:
    R: np.ndarray              # board -> camera rotation
    t: np.ndarray              # board origin in the camera, metres
    corners_px: np.ndarray     # (N, 2), NaN where not in the image
    partial: bool

    @property
    def visible(self) -> int:
        return int(np.sum(np.isfinite(self.corners_px[:, 0])))


def project_corners(lens, board: Board, R: np.ndarray, t: np.ndarray) -> np.ndarray:
    """True pixel position of every corner (mrcal.project), NaN outside the image or the lens' field."""
    p = board.corners() @ R.T + t
    q = project(p, lens)
    W, H = imagersize(lens)
    angle = np.arctan2(np.hypot(p[:, 0], p[:, 1]), p[:, 2])
    ok = (angle < max_valid_angle_rad(lens)) & (q[:, 0] >= -0.5) & (q[:, 0] <= W - 0.5) & \
        (q[:, 1] >= -0.5) & (q[:, 1] <= H - 0.5)
    q[~ok] = np.nan
    return q


def _facing_rotation(z: np.ndarray) -> np.ndarray:
    """Board axes (columns) with the normal along z and the board's x as close to the camera's x."""
    x = np.array([1.0, 0.0, 0.0]) - z[0] * z
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return np.stack([x, y, z], axis=1)


def _target_pixel(rng: np.random.Generator, diff: Difficulty, W: int, H: int) -> tuple[np.ndarray, bool, bool]:
    """Where the board's centre should appear; whether it is an edge placement and may be partial."""
    if rng.random() < diff.edge_prob:
        partial = rng.random() < diff.partial_prob
        lo, hi = (-0.05, 0.12) if partial else (0.12, 0.25)
        fx = rng.uniform(lo, hi)
        fy = rng.uniform(lo, hi)
        # 0 corner, 1 left/right edge, 2 top/bottom edge
        kind = 0 if rng.random() < diff.corner_share else 1 + int(rng.integers(2))
        if kind == 1:
            fy = rng.uniform(0.2, 0.8)
        elif kind == 2:
            fx = rng.uniform(0.2, 0.8)
        if rng.random() < 0.5:
            fx = 1 - fx
        if rng.random() < 0.5:
            fy = 1 - fy
        return np.array([fx * W, fy * H]), True, partial
    span = 0.2 if diff.edge_prob == 0 else 0.35
    return np.array([rng.uniform(0.5 - span, 0.5 + span) * W, rng.uniform(0.5 - span, 0.5 + span) * H]), False, False


def sample_view(rng: np.random.Generator, lens, board: Board, diff: Difficulty,
                max_tries: int = 400) -> BoardView:
    W, H = imagersize(lens)
    f = float(lens.intrinsics()[1][0])
    board_w = (board.width + 1) * board.square_m
    for _ in range(max_tries):
        target, edge, partial = _target_pixel(rng, diff, W, H)
        v = unproject(target[None, :], lens)[0]
        width_px = rng.uniform(*diff.width_frac) * W
        dist = f * board_w / width_px
        R = _facing_rotation(v)
        phi = rng.uniform(0, 2 * math.pi)
        axis = R[:, 0] * math.cos(phi) + R[:, 1] * math.sin(phi)
        tilt = math.radians(diff.max_tilt_deg) * math.sqrt(rng.uniform(0, 1))
        roll = math.radians(rng.uniform(-diff.max_roll_deg, diff.max_roll_deg))
        R = rotvec_to_matrix(axis * tilt) @ R @ rotvec_to_matrix(np.array([0, 0, roll]))
        t = dist * v - R @ board.centre()
        q = project_corners(lens, board, R, t)
        ok = np.isfinite(q[:, 0])
        n_ok = int(ok.sum())
        p = board.corners() @ R.T + t
        if np.any(p[:, 2] <= 0.05):
            continue
        if partial:
            if n_ok == board.n or n_ok < MIN_PARTIAL_SHARE * board.n:
                continue
        else:
            if n_ok < board.n:
                continue
            if np.any((q[:, 0] < FULL_MARGIN_PX) | (q[:, 0] > W - 1 - FULL_MARGIN_PX) |
                      (q[:, 1] < FULL_MARGIN_PX) | (q[:, 1] > H - 1 - FULL_MARGIN_PX)):
                continue
        # neighbour spacing in the image, along both grid directions, where both corners are seen
        g = q.reshape(board.height, board.width, 2)
        d = np.concatenate([np.linalg.norm(np.diff(g, axis=1), axis=2).ravel(),
                            np.linalg.norm(np.diff(g, axis=0), axis=2).ravel()])
        d = d[np.isfinite(d)]
        if d.size == 0 or d.min() < diff.min_square_px:
            continue
        return BoardView(R, t, q, n_ok < board.n)
    raise RuntimeError(f"no board pose satisfies difficulty {diff.name!r} for a {board.width}x{board.height} "
                       f"board of {board.square_m} m squares in {max_tries} tries; use a smaller board")
