"""Detection over many files, as `calibrate detect` and `calibrate thermal` need it."""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

from platform_tools.rig.progress import progress

from .detector import Detection
from .images import ImageError, load_image
from .targets import check_target_board, detect_target


@dataclass(frozen=True)
class FileDetection:
    path: Path
    detection: Detection | None      # None when the file was not a usable image
    error: str = ""                  # the ImageError message in that case
    imagersize: tuple[int, int] | None = None


def detect_files(files: Sequence[Path], board: tuple[int, int], *, strict: bool = True,
                 show_progress: bool = True, target: str = "checkerboard") -> list[FileDetection]:
    """Detect the board (a ``target``: calibration/targets) in every file. ``strict``: a bad file
    raises ImageError (the caller reports it and stops); otherwise it is recorded and skipped."""
    check_target_board(target, board)
    out = []
    items = progress(files, desc="detecting", total=len(files), unit="image") if show_progress else files
    for path in items:
        try:
            img = load_image(path)
        except ImageError as exc:
            if strict:
                raise
            out.append(FileDetection(Path(path), None, str(exc)))
            continue
        det = detect_target(img, board, target)
        out.append(FileDetection(Path(path), det, "", (img.shape[1], img.shape[0])))
    return out


LARGER_MIN_VIEWS = 2        # views showing more corners than --board before the whole set is refused
LARGER_MIN_SHARE = 0.2      # ... and this share of the views in which a grid was found
_LARGER = re.compile(r"found a (\d+)x(\d+) grid of corners, larger than")


def board_size_problem(results: Sequence[FileDetection], board: tuple[int, int]) -> str:
    """Why ``board`` cannot be the board these views show, or "": when at least LARGER_MIN_VIEWS views,
    and LARGER_MIN_SHARE of the views with a grid, show a grid of more corners than ``board`` (each
    refused on its own), the board is larger than --board, and the views labelled are not to be
    trusted either: a partial view sees one edge of the board, and labels W x H corners from that edge,
    a left-anchored and a right-anchored view then name different corners alike (a 10x7 board under
    --board 9x7: 16 of 20 views refused as 10x7, the other 4 labelled, 3 of them a column off the
    first's). One line naming the largest size found."""
    W, H = board
    sizes, with_grid = [], 0
    for r in results:
        d = r.detection
        if d is None:
            continue
        m = _LARGER.search(d.reason or "")
        if m:
            sizes.append((int(m.group(1)), int(m.group(2))))
        if d.detected or m:
            with_grid += 1
    if len(sizes) < LARGER_MIN_VIEWS or len(sizes) < LARGER_MIN_SHARE * max(with_grid, 1):
        return ""
    big = max(sizes, key=lambda s: s[0] * s[1])
    return (f"{len(sizes)} of {with_grid} views show a grid of corners larger than the --board {W}x{H} (up to "
            f"{big[0]}x{big[1]}): give the board's inner corners, e.g. --board {big[0]}x{big[1]}")
