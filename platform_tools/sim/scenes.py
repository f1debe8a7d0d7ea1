"""What the simulated cameras see: a warm object moving over a background, seen by all four cameras.

A simple renderer of this project's own (calibration.synth renders calibration boards, not a scene
over time): thermal frames are raw 16-bit counts with noise, ZED frames 8-bit grey as JPEG, depth a
tilted plane in metres. Replace with calibration.synth scenes when it offers them.
"""
from __future__ import annotations

import cv2
import numpy as np


def _blob(w: int, h: int, t_s: float, phase: float) -> np.ndarray:
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    cx = w * (0.5 + 0.3 * np.sin(2 * np.pi * 0.2 * t_s + phase))
    cy = h * (0.5 + 0.2 * np.cos(2 * np.pi * 0.13 * t_s))
    r = 0.12 * min(w, h)
    return np.exp(-((xx - cx) ** 2 + (yy - cy) ** 2) / (2 * r * r))


def thermal(w: int, h: int, t_s: float, side_shift: float, rng: np.random.Generator) -> np.ndarray:
    base = 7500 + 400 * np.linspace(0, 1, h, dtype=np.float32)[:, None]
    img = base + 1500 * _blob(w, h, t_s, side_shift) + rng.normal(0, 8, (h, w))
    return np.clip(img, 0, 65535).astype(np.uint16)


def zed_jpeg(w: int, h: int, t_s: float, side_shift: float, rng: np.random.Generator) -> bytes:
    yy, xx = np.mgrid[0:h, 0:w]
    checker = ((xx // 16 + yy // 16) % 2) * 60 + 80
    img = checker + 90 * _blob(w, h, t_s, side_shift) + rng.normal(0, 3, (h, w))
    ok, buf = cv2.imencode(".jpg", np.clip(img, 0, 255).astype(np.uint8), [cv2.IMWRITE_JPEG_QUALITY, 85])
    assert ok
    return buf.tobytes()


def depth(w: int, h: int) -> np.ndarray:
    return (2.0 + 1.5 * np.linspace(0, 1, h, dtype=np.float32)[:, None] * np.ones((1, w), np.float32))
