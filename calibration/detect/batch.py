"""Detection over many files, as `calibrate detect` and `calibrate thermal` need it."""
from __future__ import annotations

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
