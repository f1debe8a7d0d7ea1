"""What 8-bit input costs, for the report: a Boson streaming 8-bit AGC video instead of its 16-bit counts.

An 8-bit frame has gone through the camera's automatic gain control: a per-frame, non-linear
histogram mapping quantised to 256 levels, so a faint board spans a few grey levels and the corner
positions carry the steps. The figures below were measured by bench/bench_calib_lenses.py on the same
scenes rendered twice, as 16-bit counts and through the 8-bit AGC (calibration/synth/agc.py, a
plausible model of the Boson's AGC, not FLIR's exact algorithm), "real" conditions, 40 images, seed 11:
see docs/calibration-synthetic.md for the whole table. They are synthetic figures: on a real Boson
the cost depends on its AGC settings.
"""
from __future__ import annotations

from dataclasses import dataclass

# measured on the tree of 2026-12-02 (the detector and default solver of commit 11656a5, which chose
# Kannala-Brandt on both sets): bench/bench_calib_lenses.py's sets --n 40 --seed 11 --conditions real, --outputs
# y16 and agc8, truth lens opencv8; corners by bench_detection.evaluate, model by bench_calib_lenses.model_error
# (docs/calibration-synthetic.md). 24 of 24 complete boards on both; whole-image model error 0.039 / 0.100 px
DATA = "synthetic 'real' scenes, 40 images, seed 11, the rig's nominal OPENCV8 lens"
CORNER_RMS_16_PX = 0.025          # complete boards, corners within 1 px of the truth
CORNER_RMS_8_PX = 0.169
MODEL_CENTRAL_16_PX = 0.029       # projection difference to the truth lens over the central 80 %
MODEL_CENTRAL_8_PX = 0.073


@dataclass(frozen=True)
class DepthNote:
    bit_depth: int
    text: str


def note(bit_depth: int | None) -> DepthNote | None:
    """The report's sentence for 8-bit input (None for 16-bit or unknown)."""
    if bit_depth is None or bit_depth > 8:
        return None
    return DepthNote(bit_depth, (
        f"8-bit input (AGC video): accuracy is reduced; on the same scenes ({DATA}) 8-bit AGC frames gave "
        f"corner errors of {CORNER_RMS_8_PX:.3f} px RMS against {CORNER_RMS_16_PX:.3f} px from 16-bit counts "
        f"({CORNER_RMS_8_PX / CORNER_RMS_16_PX:.1f}x) and a lens {MODEL_CENTRAL_8_PX:.3f} px off over the central "
        f"80% against {MODEL_CENTRAL_16_PX:.3f} px; record 16-bit (Y16) frames for calibration"))
