"""The microbolometer: optics blur, vignetting and warm-housing offset, gain non-uniformity, column
fixed-pattern noise, temporal noise, 16-bit counts (raw Y16, about 14 bits used, like a Boson).

A :class:`Sensor` is one camera between two flat-field corrections: its gain map and column
pattern are drawn once (from the dataset's seed) and stay for every image of a dataset.
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from .difficulty import Difficulty
from .scene import AMBIENT_K, smooth_field

COUNTS_PER_K = 40.0      # responsivity: ~0.025 K per count
COUNTS_AT_AMBIENT = 7500.0


def counts(above_ambient_k: np.ndarray) -> np.ndarray:
    """The microbolometer's response, the one temperature -> Boson counts model of the project: raw counts
    (float32, same shape, neither rounded nor clipped) of a signal ``above_ambient_k`` kelvin above
    :data:`~calibration.synth.scene.AMBIENT_K` (``COUNTS_AT_AMBIENT`` at ambient, ``COUNTS_PER_K`` per kelvin)."""
    return COUNTS_AT_AMBIENT + COUNTS_PER_K * np.asarray(above_ambient_k, np.float32)


@dataclass
class Sensor:
    gain: np.ndarray          # (H, W) relative responsivity (vignetting and non-uniformity)
    offset_k: np.ndarray      # (H, W) kelvin: warm housing and column pattern
    noise_k: float

    @staticmethod
    def make(rng: np.random.Generator, shape: tuple[int, int], diff: Difficulty) -> "Sensor":
        H, W = shape
        y, x = np.mgrid[0:H, 0:W].astype(np.float32)
        rho2 = ((x - (W - 1) / 2) ** 2 + (y - (H - 1) / 2) ** 2) / ((W / 2) ** 2 + (H / 2) ** 2)
        gain = (1.0 - diff.vignette * rho2 ** 2) * (1.0 + smooth_field(rng, shape, (6, 7), diff.gain_nonuniformity))
        columns = rng.normal(0.0, diff.column_fpn_k, size=W).astype(np.float32)
        offset = diff.housing_k * rho2 + columns[None, :]
        return Sensor(gain.astype(np.float32), offset.astype(np.float32), diff.noise_k)

    def expose(self, rng: np.random.Generator, scene_k: np.ndarray, blur_px: float) -> np.ndarray:
        """Scene temperatures (H, W) to a uint16 frame of counts."""
        img = cv2.GaussianBlur(scene_k.astype(np.float32) - AMBIENT_K, (0, 0), blur_px)
        drift = rng.normal(0.0, 0.2)                    # offset drift since the last FFC
        img = self.gain * img + self.offset_k + drift
        img += rng.normal(0.0, self.noise_k, size=img.shape).astype(np.float32)
        return np.clip(np.rint(counts(img)), 0, 65535).astype(np.uint16)
