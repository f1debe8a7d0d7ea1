"""corners.vnl: detected chessboard corners in the vnlog form mrcal-calibrate-cameras
--corners-cache reads.

    # filename x y level
    000.png 321.52 240.11 0
    ...                      (all W*H rows of a detected board, grid order: top-left first, across first)
    001.png - - -            (an image without a detection)

A corner of a partial board that was not found is ``- -`` with level ``-``. With ``weights=True``
the fourth column is a weight instead (``# filename x y weight``, for --corners-cache-has-weights):
2^-level, 0 never written (a missing corner is ``-``).
"""
from __future__ import annotations

import io
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable

import numpy as np

from platform_tools.rig import atomic


@dataclass(frozen=True)
class BoardCorners:
    """One image's row group: ``corners`` (N, 2) NaN where missing, ``level`` (N,) -1 where missing;
    ``corners`` is None for an image without a detection."""
    filename: str
    corners: np.ndarray | None
    level: np.ndarray | None


def _fmt(v: float) -> str:
    return f"{v:.4f}"


def format_corners(rows: Iterable[BoardCorners], *, weights: bool = False) -> str:
    out = io.StringIO()
    out.write(f"# filename x y {'weight' if weights else 'level'}\n")
    for r in rows:
        name = r.filename
        if any(ch.isspace() for ch in name) or name.startswith("#"):
            raise ValueError(f"{name!r}: file names in a corners file cannot contain spaces or start with #")
        if r.corners is None:
            out.write(f"{name} - - -\n")
            continue
        for (x, y), lv in zip(r.corners, r.level):
            if not (np.isfinite(x) and np.isfinite(y)) or lv < 0:
                out.write(f"{name} - - -\n")
            else:
                w = f"{2.0 ** -float(lv):.6g}" if weights else str(int(lv))
                out.write(f"{name} {_fmt(x)} {_fmt(y)} {w}\n")
    return out.getvalue()


def write_corners(path: str | Path, rows: Iterable[BoardCorners], *, weights: bool = False) -> Path:
    """Write a corners file atomically."""
    return atomic.write_text(path, format_corners(rows, weights=weights))


class CornersFileError(ValueError):
    """A malformed corners file; ``str()`` names the file and line."""


def read_corners(path: str | Path, n_corners: int | None = None) -> list[BoardCorners]:
    """Read a corners file (ours or mrgingham's). Rows of one image must be consecutive. A detected
    board has ``n_corners`` rows when given (checked), else however many rows it has. The fourth
    column is returned as ``level`` whatever the header calls it (a weight file gives weights)."""
    path = Path(path)
    try:
        text = path.read_text()
    except (OSError, UnicodeDecodeError) as exc:
        raise CornersFileError(f"{path}: cannot read ({exc})") from None
    groups: list[tuple[str, list]] = []
    header = None
    for lineno, line in enumerate(text.splitlines(), 1):
        s = line.strip()
        if not s:
            continue
        if s.startswith("#"):
            if header is None and s.lstrip("#").split()[:3] == ["filename", "x", "y"]:
                header = s.lstrip("#").split()
            continue
        parts = s.split()
        if len(parts) != 4:
            raise CornersFileError(f"{path}:{lineno}: expected 4 columns (filename x y level), got {len(parts)}")
        name, xs, ys, ls = parts
        try:
            x = np.nan if xs == "-" else float(xs)
            y = np.nan if ys == "-" else float(ys)
            lv = -1.0 if ls == "-" else float(ls)
        except ValueError:
            raise CornersFileError(f"{path}:{lineno}: not a number in {s!r}") from None
        if not groups or groups[-1][0] != name:
            groups.append((name, []))
        groups[-1][1].append((x, y, lv))
    if header is None:
        raise CornersFileError(f"{path}: no '# filename x y level' header; not a corners vnlog")
    out = []
    seen = set()
    for name, rows in groups:
        if name in seen:
            raise CornersFileError(f"{path}: rows of {name} are not consecutive")
        seen.add(name)
        a = np.array(rows, float)
        if len(rows) == 1 and np.isnan(a[0, 0]) and a[0, 2] < 0:
            out.append(BoardCorners(name, None, None))
            continue
        if n_corners is not None and len(rows) != n_corners:
            raise CornersFileError(f"{path}: {name} has {len(rows)} corner rows, expected {n_corners} "
                                   f"(W*H of the board)")
        lv = a[:, 2].copy()
        lv[np.isnan(a[:, 0])] = -1
        out.append(BoardCorners(name, a[:, :2], lv))
    return out
