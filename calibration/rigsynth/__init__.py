"""Synthetic synchronised image sets of the whole rig (ZED X left/right in RGB, both Bosons in
thermal), all seeing the same board, from a rig whose true extrinsics differ from the CAD ones.
Built on calibration.synth's public pieces; see docs/extrinsics.md."""
from .render import CAMERA_FOLDERS, render_rig_dataset, true_lenses

__all__ = ["render_rig_dataset", "true_lenses", "CAMERA_FOLDERS"]
