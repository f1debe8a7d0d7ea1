"""A pinhole view of a calibrated lens' images: for every pixel of a pinhole camera with a stated
horizontal field of view (looking along the lens' optical axis, centred, square pixels), the ray
is projected through the lens (model.Lens.project: mrcal.project or cv2.fisheye.projectPoints) and
the image sampled there with cv2.remap (bilinear; outside the calibrated image: 0). Straight lines
in the scene are straight in the result. Also the before/after figure: one image and its
rectification side by side, contrast-stretched alike, as an 8-bit PNG."""
from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from .model import Lens

MAX_FOV_DEG = 170.0
FIGURE_GAP = 8
STRETCH_PCT = (1.0, 99.0)


@dataclass(frozen=True)
class Pinhole:
    f: float
    cx: float
    cy: float
    size: tuple[int, int]
    hfov_deg: float

    def intrinsics(self) -> list[float]:
        return [self.f, self.f, self.cx, self.cy]


def pinhole_for(size: tuple[int, int], hfov_deg: float) -> Pinhole:
    """A W x H pinhole whose horizontal field of view (edge to edge) is ``hfov_deg``."""
    if not 1.0 <= hfov_deg <= MAX_FOV_DEG:
        raise ValueError(f"field of view {hfov_deg} deg: a pinhole view needs 1 to {MAX_FOV_DEG:.0f} deg")
    W, H = int(size[0]), int(size[1])
    f = (W / 2.0) / math.tan(math.radians(hfov_deg) / 2.0)
    return Pinhole(f, (W - 1) / 2.0, (H - 1) / 2.0, (W, H), float(hfov_deg))


def remap_tables(lens: Lens, pin: Pinhole) -> tuple[np.ndarray, np.ndarray]:
    """cv2.remap's (map_x, map_y), float32 (H, W): where in the lens' image each pinhole pixel looks."""
    W, H = pin.size
    u, v = np.meshgrid(np.arange(W, dtype=float), np.arange(H, dtype=float))
    rays = np.stack([(u - pin.cx) / pin.f, (v - pin.cy) / pin.f, np.ones_like(u)], -1).reshape(-1, 3)
    q = np.asarray(lens.project(rays), float).reshape(H, W, 2)
    Wl, Hl = lens.imagersize
    bad = ~np.all(np.isfinite(q), axis=2) | (q[..., 0] < -0.5) | (q[..., 1] < -0.5) \
        | (q[..., 0] > Wl - 0.5) | (q[..., 1] > Hl - 0.5)
    q[bad] = -10.0                                    # outside: cv2.remap's constant border
    return q[..., 0].astype(np.float32), q[..., 1].astype(np.float32)


def rectify(image: np.ndarray, maps: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """The pinhole view of ``image`` (same dtype)."""
    src = image if image.dtype in (np.uint8, np.uint16, np.float32) else image.astype(np.float32)
    return cv2.remap(src, maps[0], maps[1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0)


def _to8(img: np.ndarray, lo: float, hi: float) -> np.ndarray:
    return np.clip((img.astype(float) - lo) * (255.0 / max(hi - lo, 1e-9)), 0, 255).astype(np.uint8)


def before_after(raw: np.ndarray, rect: np.ndarray, labels: tuple[str, str]) -> np.ndarray:
    """The figure: ``raw`` left, ``rect`` right (8-bit, the same stretch from the raw image's 1st-99th
    percentile; the rectified image's empty border stays black), each labelled at its top left."""
    lo, hi = np.percentile(raw, STRETCH_PCT)
    a, b = _to8(raw, lo, hi), _to8(rect, lo, hi)
    H = max(a.shape[0], b.shape[0])
    out = np.zeros((H, a.shape[1] + FIGURE_GAP + b.shape[1]), np.uint8)
    out[:a.shape[0], :a.shape[1]] = a
    out[:b.shape[0], a.shape[1] + FIGURE_GAP:] = b
    for x0, text in ((0, labels[0]), (a.shape[1] + FIGURE_GAP, labels[1])):
        cv2.putText(out, text, (x0 + 6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.5, 0, 3, cv2.LINE_AA)
        cv2.putText(out, text, (x0 + 6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.5, 255, 1, cv2.LINE_AA)
    return out
