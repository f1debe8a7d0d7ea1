"""Board observations: the detected corners of every image, in the arrays mrcal solves from.

One :class:`BoardObservations` holds, for N images of a W x H (inner corners) chessboard, the pixel
position of every corner in grid order (top-left first, horizontal first; NaN where a corner was not
seen) and its weight (1 = full-resolution detection, 2^-level for a coarser one). mrcal wants these
as ``observations_board`` of shape (N, H, W, 3) = (x, y, weight) with weight < 0 for a missing corner.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class BoardObservations:
    names: list[str]               # one per image (file name as written in corners.vnl)
    corners: np.ndarray            # (N, H*W, 2) pixels, NaN where not seen
    weights: np.ndarray            # (N, H*W), > 0 where seen
    board: tuple[int, int]         # (W, H) inner corners
    square_m: float
    imagersize: tuple[int, int]    # (width, height) pixels
    missed: list[str] = field(default_factory=list)   # images with no board at all
    missed_why: list = field(default_factory=list)     # why, per image (calibration/report/missed.py Missed)
    bit_depth: int | None = None                       # of the input images (8: an AGC'd stream), None: unknown

    def __post_init__(self) -> None:
        w, h = self.board
        self.corners = np.asarray(self.corners, dtype=float).reshape(len(self.names), w * h, 2)
        self.weights = np.asarray(self.weights, dtype=float).reshape(len(self.names), w * h)
        seen = np.isfinite(self.corners).all(axis=-1) & (self.weights > 0)
        self.corners[~seen] = np.nan
        self.weights[~seen] = 0.0

    @property
    def n(self) -> int:
        return len(self.names)

    def seen(self) -> np.ndarray:
        """(N, H*W) bool: the corner was detected."""
        return np.isfinite(self.corners).all(axis=-1)

    def counts(self) -> np.ndarray:
        return self.seen().sum(axis=1)

    def subset(self, keep: np.ndarray | list[int]) -> "BoardObservations":
        keep = np.asarray(keep)
        if keep.dtype == bool:
            keep = np.flatnonzero(keep)
        return BoardObservations([self.names[i] for i in keep], self.corners[keep], self.weights[keep],
                                 self.board, self.square_m, self.imagersize, list(self.missed),
                                 list(self.missed_why), self.bit_depth)

    def mrcal_array(self) -> np.ndarray:
        """observations_board for mrcal.optimize: (N, H, W, 3) float64, weight -1 where not seen."""
        w, h = self.board
        out = np.empty((self.n, h, w, 3))
        seen = self.seen()
        xy = np.where(seen[..., None], self.corners, -1.0)
        out[..., :2] = xy.reshape(self.n, h, w, 2)
        out[..., 2] = np.where(seen, self.weights, -1.0).reshape(self.n, h, w)
        return out

    def board_points_m(self) -> np.ndarray:
        """(H*W, 3) corner positions in the board frame, metres (mrcal's ref_calibration_object)."""
        w, h = self.board
        ij = np.stack(np.meshgrid(np.arange(w), np.arange(h)), axis=-1).reshape(-1, 2)
        return np.column_stack([ij * self.square_m, np.zeros(len(ij))])


def from_detections(names: list[str], detections: list[np.ndarray | None], board: tuple[int, int],
                    square_m: float, imagersize: tuple[int, int],
                    weights: list[np.ndarray | None] | None = None) -> BoardObservations:
    """Build observations from per-image detector output; ``None`` (or all-NaN) means no board.
    Images without a board are kept by name in ``missed``."""
    w, h = board
    kept_names, kept_corners, kept_weights, missed = [], [], [], []
    for i, (name, c) in enumerate(zip(names, detections)):
        if c is None or not np.isfinite(np.asarray(c, dtype=float)).any():
            missed.append(name)
            continue
        c = np.asarray(c, dtype=float).reshape(w * h, 2)
        wt = None if weights is None else weights[i]
        wt = np.ones(w * h) if wt is None else np.asarray(wt, dtype=float).reshape(w * h)
        kept_names.append(name)
        kept_corners.append(c)
        kept_weights.append(wt)
    corners = np.array(kept_corners).reshape(len(kept_names), w * h, 2)
    wts = np.array(kept_weights).reshape(len(kept_names), w * h)
    return BoardObservations(kept_names, corners, wts, board, square_m, imagersize, missed)
