"""Synchronised image sets of the rig's four cameras, paired, and their detected board corners.

Layout: ``DIR/zed_left/``, ``DIR/zed_right/``, ``DIR/thermal_left/``, ``DIR/thermal_right/``, one
image per camera per set. Files are paired by name: when every name (without its extension) is an
integer it is a timestamp in ns and each ZED left frame takes, in every other camera, the frame
nearest in time within the pair tolerance; otherwise names must be equal across the folders
(``000.png`` with ``000.png``). A file that pairs with nothing is bad input (the message names it).
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from .cad import CAMERAS

log = logging.getLogger("calibration.rig")
IMAGE_SUFFIXES = (".png", ".tif", ".tiff", ".jpg", ".jpeg", ".pgm", ".bmp")
MIN_CORNERS = 12          # a view with fewer corners is not used


class SetError(Exception):
    """Bad image sets: one line naming the file or folder."""


@dataclass
class ImageSet:
    key: str                       # the ZED left file's name without extension
    files: dict[str, Path]         # camera -> file
    stamps_ns: dict[str, int] | None = None


@dataclass
class RigObservations:
    """Corners of every set (rows) and camera (columns): (N, H*W, 2), NaN where not seen."""
    sets: list[ImageSet]
    corners: dict[str, np.ndarray]
    weights: dict[str, np.ndarray]
    imagersizes: dict[str, tuple[int, int]]
    board: tuple[int, int]
    square_m: float
    dropped: list[str] = field(default_factory=list)

    @property
    def n(self) -> int:
        return len(self.sets)

    def seen(self, cam: str) -> np.ndarray:
        """(N,) the camera saw enough of the board in each set."""
        return np.isfinite(self.corners[cam][..., 0]).sum(axis=1) >= MIN_CORNERS

    def subset(self, keep) -> "RigObservations":
        keep = np.flatnonzero(np.asarray(keep)) if np.asarray(keep).dtype == bool else np.asarray(keep)
        return RigObservations([self.sets[i] for i in keep], {c: v[keep] for c, v in self.corners.items()},
                               {c: v[keep] for c, v in self.weights.items()}, dict(self.imagersizes), self.board,
                               self.square_m, list(self.dropped))


def _images(folder: Path) -> list[Path]:
    return sorted(p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES)


def find_sets(root: Path | str, tolerance_ms: float) -> list[ImageSet]:
    root = Path(root)
    if not root.is_dir():
        raise SetError(f"--images {root}: not a folder")
    missing = [c for c in CAMERAS if not (root / c).is_dir()]
    if missing:
        raise SetError(f"--images {root}: no {missing[0]}/ folder (a set needs one image from each of "
                       f"{', '.join(c + '/' for c in CAMERAS)})")
    files = {c: _images(root / c) for c in CAMERAS}
    empty = [c for c in CAMERAS if not files[c]]
    if empty:
        raise SetError(f"--images {root}/{empty[0]}: no images (a set needs one image from every camera)")
    for c in CAMERAS:
        stems = [p.stem for p in files[c]]
        if len(set(stems)) != len(stems):
            dup = next(s for s in stems if stems.count(s) > 1)
            raise SetError(f"{root / c}: two images named {dup}.* ; one image per set")
    stamped = all(p.stem.isdigit() for c in CAMERAS for p in files[c])
    return _pair_stamps(root, files, tolerance_ms) if stamped else _pair_names(root, files)


def _pair_names(root: Path, files: dict[str, list[Path]]) -> list[ImageSet]:
    by = {c: {p.stem: p for p in files[c]} for c in CAMERAS}
    keys = set(by["zed_left"])
    for c in CAMERAS:
        extra = sorted(set(by[c]) ^ keys)
        if extra:
            k = extra[0]
            has = [d for d in CAMERAS if k in by[d]]
            lacks = [d for d in CAMERAS if k not in by[d]]
            raise SetError(f"{root / has[0] / by[has[0]][k].name}: no image named {k}.* in {lacks[0]}/; every set "
                           f"needs one image per camera with the same name ({len(extra)} such name(s))")
    return [ImageSet(k, {c: by[c][k] for c in CAMERAS}) for k in sorted(keys)]


def _pair_stamps(root: Path, files: dict[str, list[Path]], tolerance_ms: float) -> list[ImageSet]:
    tol = int(round(tolerance_ms * 1e6))
    stamps = {c: np.array([int(p.stem) for p in files[c]], dtype=np.int64) for c in CAMERAS}
    order = {c: np.argsort(stamps[c]) for c in CAMERAS}
    used = {c: set() for c in CAMERAS}
    sets = []
    for i in order["zed_left"]:
        t = int(stamps["zed_left"][i])
        chosen = {"zed_left": i}
        for c in CAMERAS:
            if c == "zed_left":
                continue
            d = np.abs(stamps[c] - t)
            j = int(np.argmin(d))
            if d[j] > tol:
                raise SetError(f"{root / 'zed_left' / files['zed_left'][i].name}: no {c}/ image within "
                               f"{tolerance_ms:g} ms of it (nearest {d[j] / 1e6:.1f} ms away); the timestamps do "
                               f"not pair (--pair-tolerance-ms)")
            if j in used[c]:
                raise SetError(f"{root / c / files[c][j].name}: pairs with two zed_left/ images; the timestamps "
                               f"do not pair one to one (--pair-tolerance-ms {tolerance_ms:g} is too wide?)")
            used[c].add(j)
            chosen[c] = j
        sets.append(ImageSet(files["zed_left"][i].stem, {c: files[c][j] for c, j in chosen.items()},
                             {c: int(stamps[c][j]) for c, j in chosen.items()}))
    for c in CAMERAS:
        left = [files[c][j] for j in range(len(files[c])) if c != "zed_left" and j not in used[c]]
        if left:
            raise SetError(f"{root / c / left[0].name}: pairs with no zed_left/ image within {tolerance_ms:g} ms "
                           f"({len(left)} such file(s) in {c}/); the timestamps do not pair")
    return sets


def read_gray(path: Path) -> np.ndarray:
    img = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if img is None:
        raise SetError(f"{path}: not a readable image (corrupt or not an image)")
    if img.ndim == 3:
        img = cv2.cvtColor(img[..., :3], cv2.COLOR_BGR2GRAY)
    return img


def detect_sets(sets: list[ImageSet], board: tuple[int, int], square_m: float, *,
                show_progress: bool = False) -> RigObservations:
    from platform_tools.rig.progress import progress

    from ..detect import detect_corners
    W, H = board
    corners = {c: np.full((len(sets), W * H, 2), np.nan) for c in CAMERAS}
    weights = {c: np.zeros((len(sets), W * H)) for c in CAMERAS}
    sizes: dict[str, set] = {c: set() for c in CAMERAS}
    jobs = [(i, c) for i in range(len(sets)) for c in CAMERAS]
    if show_progress:
        jobs = progress(jobs, desc="detecting", total=len(jobs), unit="image")
    for i, c in jobs:
        img = read_gray(sets[i].files[c])
        sizes[c].add((img.shape[1], img.shape[0]))
        d = detect_corners(img, board)
        if d.detected:
            corners[c][i] = d.corners
            weights[c][i] = np.where(np.isfinite(d.corners[:, 0]), d.weight, 0.0)
    for c in CAMERAS:
        if len(sizes[c]) > 1:
            raise SetError(f"{c}/: images of different sizes {sorted(sizes[c])}; one camera, one size")
    return RigObservations(sets, corners, weights, {c: sizes[c].pop() for c in CAMERAS}, tuple(board), square_m)


def usable(obs: RigObservations, min_sets: int = 3) -> RigObservations:
    """Keep the sets where at least two cameras see the board; every camera must then see it in
    ``min_sets`` of them (else bad input: its extrinsics cannot be solved)."""
    seen = np.stack([obs.seen(c) for c in CAMERAS], axis=1)     # (N, 4)
    multi = seen.sum(axis=1) >= 2
    if not multi.any():
        only = [f"{s.key}: {', '.join(c for c, v in zip(CAMERAS, row) if v) or 'no camera'}"
                for s, row in zip(obs.sets, seen)]
        raise SetError(f"no set shows the board to more than one camera ({'; '.join(only[:3])}"
                       f"{' ...' if len(only) > 3 else ''}); extrinsics need the same board seen by several cameras")
    dropped = [s.key for s, m in zip(obs.sets, multi) if not m]
    for k in dropped:
        log.warning("set %s: the board is seen by one camera only; set not used", k)
    out = obs.subset(multi)
    out.dropped = dropped
    for j, c in enumerate(CAMERAS):
        cnt = int(seen[multi, j].sum())
        if cnt < min_sets:
            raise SetError(f"{c}: the board is seen together with another camera in {cnt} set(s), at least "
                           f"{min_sets} are needed to solve its extrinsics (is the board warm enough for the "
                           f"thermal cameras, in view of every camera?)")
    return out
