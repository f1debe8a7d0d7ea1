"""Stereo board views on disk: ``DIR/left/`` and ``DIR/right/`` (or ``DIR/thermal_left/`` and
``DIR/thermal_right/``, the layout ``calibrate rig`` reads), one image per board pose in each, paired by
file name without its extension (``007.png`` with ``007.png``; a recording's timestamps are not paired
here: name the pairs alike). A file without its partner is bad input, named.

Corners are held as mrcal wants them: (N, H*W, 2) pixels in grid order, NaN where not seen.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from calibration.detect.images import IMAGE_SUFFIXES

FOLDERS = (("left", "right"), ("thermal_left", "thermal_right"))
MIN_CORNERS = 12          # a view with fewer corners in one camera is not a shared view


class StereoInputError(Exception):
    """Bad stereo input: ``str()`` is one line naming the file or folder and what is wrong."""


@dataclass
class StereoObservations:
    names: list[str]                 # (N,) pair names (the shared file stem)
    left: np.ndarray                 # (N, H*W, 2) pixels, NaN where not seen
    right: np.ndarray                # (N, H*W, 2)
    weights_left: np.ndarray         # (N, H*W) mrcal weights, 0 where not seen
    weights_right: np.ndarray        # (N, H*W)
    board: tuple[int, int]           # (W, H) inner corners
    square_m: float

    @property
    def n(self) -> int:
        return len(self.names)

    def shared(self, min_corners: int = MIN_CORNERS) -> np.ndarray:
        """(N,) bool: both cameras saw at least ``min_corners`` corners of this pose."""
        return ((np.isfinite(self.left[..., 0]).sum(1) >= min_corners) &
                (np.isfinite(self.right[..., 0]).sum(1) >= min_corners))

    def subset(self, keep: np.ndarray) -> "StereoObservations":
        k = np.flatnonzero(keep) if np.asarray(keep).dtype == bool else np.asarray(keep)
        return StereoObservations([self.names[i] for i in k], self.left[k], self.right[k], self.weights_left[k],
                                  self.weights_right[k], self.board, self.square_m)

    def board_points_m(self) -> np.ndarray:
        """(H*W, 3) corners in the board frame (corner (i, j) at (i s, j s, 0)), metres."""
        W, H = self.board
        j, i = np.mgrid[0:H, 0:W]
        return np.stack([i.ravel() * self.square_m, j.ravel() * self.square_m, np.zeros(W * H)], axis=1)


def _images(folder: Path) -> dict[str, Path]:
    files = sorted(p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES)
    out: dict[str, Path] = {}
    for p in files:
        if p.stem in out:
            raise StereoInputError(f"{p}: two images named {p.stem}.* in {folder}; one image per board pose")
        out[p.stem] = p
    return out


def find_pairs(root: Path | str) -> list[tuple[str, Path, Path]]:
    """(name, left file, right file) for every board pose under ``root``, sorted by name; raises
    :class:`StereoInputError` for a missing folder, an empty one or a file without its partner."""
    root = Path(root)
    if not root.is_dir():
        raise StereoInputError(f"--images {root}: no such folder")
    pair = next(((root / a, root / b) for a, b in FOLDERS if (root / a).is_dir() or (root / b).is_dir()), None)
    if pair is None:
        raise StereoInputError(f"--images {root}: no left/ and right/ folders (one image per board pose in each, "
                               f"paired by name)")
    for folder in pair:
        if not folder.is_dir():
            other = pair[1] if folder == pair[0] else pair[0]
            raise StereoInputError(f"--images {root}: {other.name}/ but no {folder.name}/ folder")
    left, right = _images(pair[0]), _images(pair[1])
    if not left and not right:
        raise StereoInputError(f"--images {root}: {pair[0].name}/ and {pair[1].name}/ hold no images")
    for have, lack, folder in ((left, right, pair[1]), (right, left, pair[0])):
        missing = sorted(set(have) - set(lack))
        if missing:
            raise StereoInputError(f"{have[missing[0]]}: no image named {missing[0]}.* in {folder}; every board "
                                   f"pose needs one image from each camera with the same name "
                                   f"({len(missing)} such image(s))")
    return [(k, left[k], right[k]) for k in sorted(left)]


def from_detections(names: list[str], left: list, right: list, board: tuple[int, int],
                    square_m: float) -> StereoObservations:
    """Observations from per-pair detections (``calibration.detect.Detection`` of each camera, or None)."""
    W, H = board

    def stack(dets):
        c = np.full((len(dets), W * H, 2), np.nan)
        w = np.zeros((len(dets), W * H))
        for i, d in enumerate(dets):
            if d is not None:
                c[i] = d.corners
                w[i] = np.where(np.isfinite(d.corners[:, 0]), d.weight, 0.0)
        return c, w
    cl, wl = stack(left)
    cr, wr = stack(right)
    return StereoObservations(list(names), cl, cr, wl, wr, (int(W), int(H)), float(square_m))
