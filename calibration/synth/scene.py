"""What surrounds the board, in image space (kelvin per pixel): a cool room with smooth gradients,
warm objects with sharp edges (monitors, radiators, windows: false corners for a detector) and a
warm hand in front of the board. Sharp shapes are drawn 4x supersampled and area-averaged."""
from __future__ import annotations

import cv2
import numpy as np

AMBIENT_K = 293.0
SS = 4


def smooth_field(rng: np.random.Generator, shape: tuple[int, int], cells: tuple[int, int], std: float) -> np.ndarray:
    """A smooth random field: a coarse normal grid upsampled bicubically."""
    coarse = rng.normal(0.0, std, size=cells).astype(np.float32)
    return cv2.resize(coarse, (shape[1], shape[0]), interpolation=cv2.INTER_CUBIC)


def background(rng: np.random.Generator, shape: tuple[int, int], clutter: int) -> np.ndarray:
    H, W = shape
    bg = AMBIENT_K + smooth_field(rng, shape, (4, 5), 1.0)
    n = int(rng.integers(0, clutter + 1)) if clutter else 0
    if n:
        canvas = np.zeros((H * SS, W * SS), np.float32)
        mask = np.zeros_like(canvas)
        for _ in range(n):
            cx, cy = rng.uniform(0, W), rng.uniform(0, H)
            w, h = rng.uniform(20, 160), rng.uniform(20, 160)
            a = rng.uniform(-0.5, 0.5)
            box = cv2.boxPoints(((cx * SS, cy * SS), (w * SS, h * SS), np.degrees(a)))
            temp = rng.uniform(-4.0, 12.0)
            cv2.fillPoly(canvas, [np.rint(box).astype(np.int32)], float(temp))
            cv2.fillPoly(mask, [np.rint(box).astype(np.int32)], 1.0)
        canvas = cv2.resize(canvas, (W, H), interpolation=cv2.INTER_AREA)
        mask = cv2.resize(mask, (W, H), interpolation=cv2.INTER_AREA)
        bg = bg + canvas  # overlapping objects add: a warm pipe in front of a warm wall
    return bg.astype(np.float32)


def hand(rng: np.random.Generator, shape: tuple[int, int], near: np.ndarray) -> tuple[np.ndarray, float]:
    """Coverage (0..1) of a hand and forearm reaching in over the point ``near`` and its temperature."""
    H, W = shape
    canvas = np.zeros((H * SS, W * SS), np.float32)
    angle = rng.uniform(0, 360)
    length, width = rng.uniform(60, 140), rng.uniform(25, 40)
    d = np.array([np.cos(np.radians(angle)), np.sin(np.radians(angle))])
    palm = near + d * rng.uniform(0, 10)
    centre = palm + d * length / 2
    c = tuple(int(x) for x in np.rint(centre * SS))
    cv2.ellipse(canvas, c, (int(length * SS / 2), int(width * SS / 2)), float(angle), 0.0, 360.0, 1.0, -1)
    cv2.circle(canvas, tuple(int(x) for x in np.rint(palm * SS)), int(width * 0.7 * SS), 1.0, -1)
    cov = cv2.resize(canvas, (W, H), interpolation=cv2.INTER_AREA)
    return cov, AMBIENT_K + rng.uniform(8.0, 13.0)
