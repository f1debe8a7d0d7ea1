"""What "easy", "real" and "hard" mean: every knob of the synthetic thermal images, per difficulty.

Temperatures are in kelvin of the scene; the sensor turns them into counts (see sensor.py).
Ranges are (low, high) drawn uniformly per image; probabilities are per image.
"""
from __future__ import annotations

from dataclasses import dataclass

DIFFICULTIES = ("easy", "real", "hard")


@dataclass(frozen=True)
class Difficulty:
    name: str
    # board signal
    contrast_k: tuple[float, float]          # temperature difference between "hot" and "cold" squares
    heat_spread_mm: tuple[float, float]      # Gaussian sigma of heat spreading across square edges
    board_gradient: float                    # relative contrast loss at the board's rim (heater falloff)
    reflection_prob: float                   # a warm reflection (the person) lowering contrast on the board
    reflection_strength: tuple[float, float]
    inverted_prob: float                     # cooled board: polarity inverted
    # geometry
    width_frac: tuple[float, float]          # apparent board width / image width
    max_tilt_deg: float
    max_roll_deg: float
    edge_prob: float                         # board placed over an image corner or edge
    partial_prob: float                      # of those, the share allowed to run out of the image
    min_square_px: float                     # smallest allowed distance between neighbouring corners
    # scene
    clutter: int                             # warm objects with sharp edges in the background (max count)
    occluder_prob: float                     # a warm hand over part of the board
    # optics and sensor
    blur_px: tuple[float, float]             # optical PSF sigma, pixels
    vignette: float                          # relative responsivity loss at the image corners
    housing_k: float                         # warm-housing offset at the image corners (kelvin)
    gain_nonuniformity: float                # low-frequency pixel gain non-uniformity (relative)
    column_fpn_k: float                      # column fixed-pattern noise (kelvin, std)
    noise_k: float                           # temporal noise (kelvin, std; Boson NETD is ~0.05 K)
    # of the edge placements, the share over an image corner (the rest: over an edge). A fisheye's
    # image corners are where its distortion is largest and where a calibration goes wrong when no
    # board was seen there; a person calibrating deliberately holds the board into each corner.
    corner_share: float = 1 / 3


LEVELS: dict[str, Difficulty] = {
    "easy": Difficulty(
        "easy", contrast_k=(12.0, 18.0), heat_spread_mm=(0.3, 0.6), board_gradient=0.0,
        reflection_prob=0.0, reflection_strength=(0.0, 0.0), inverted_prob=0.0,
        width_frac=(0.35, 0.6), max_tilt_deg=25.0, max_roll_deg=10.0, edge_prob=0.0, partial_prob=0.0,
        min_square_px=10.0, clutter=0, occluder_prob=0.0,
        blur_px=(0.5, 0.6), vignette=0.0, housing_k=0.0, gain_nonuniformity=0.0, column_fpn_k=0.0,
        noise_k=0.02),
    "real": Difficulty(
        "real", contrast_k=(4.0, 10.0), heat_spread_mm=(1.0, 2.5), board_gradient=0.25,
        reflection_prob=0.3, reflection_strength=(0.1, 0.35), inverted_prob=0.25,
        width_frac=(0.25, 0.6), max_tilt_deg=50.0, max_roll_deg=20.0, edge_prob=0.5, partial_prob=0.5,
        min_square_px=7.0, clutter=2, occluder_prob=0.0,
        blur_px=(0.6, 0.9), vignette=0.08, housing_k=0.5, gain_nonuniformity=0.03, column_fpn_k=0.08,
        noise_k=0.05, corner_share=0.5),
    "hard": Difficulty(
        "hard", contrast_k=(1.5, 5.0), heat_spread_mm=(2.0, 4.0), board_gradient=0.4,
        reflection_prob=0.6, reflection_strength=(0.2, 0.5), inverted_prob=0.5,
        width_frac=(0.2, 0.6), max_tilt_deg=65.0, max_roll_deg=25.0, edge_prob=0.5, partial_prob=0.5,
        min_square_px=6.0, clutter=5, occluder_prob=0.25,
        blur_px=(0.9, 1.4), vignette=0.15, housing_k=1.5, gain_nonuniformity=0.06, column_fpn_k=0.2,
        noise_k=0.08, corner_share=0.5),
}


def level(name: str) -> Difficulty:
    if name not in LEVELS:
        raise ValueError(f"difficulty {name!r}: choose one of {', '.join(DIFFICULTIES)}")
    return LEVELS[name]
