"""Detection over many files, as `calibrate detect` and `calibrate thermal` need it; and the one check
no single view can make: whether ``--board`` is the board the set shows (board_size_problem)."""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np

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
    target: str = "checkerboard"     # the --target the detection was made for


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
            out.append(FileDetection(Path(path), None, str(exc), target=target))
            continue
        det = detect_target(img, board, target)
        out.append(FileDetection(Path(path), det, "", (img.shape[1], img.shape[0]), target))
    return out


LARGER_MIN_VIEWS = 2        # views showing more corners than --board before the whole set is refused
LARGER_MIN_SHARE = 0.2      # ... and this share of the views in which a grid was found
_LARGER = re.compile(r"found a (\d+)x(\d+) grid of corners, larger than")


def board_size_problem(results: Sequence[FileDetection], board: tuple[int, int]) -> str:
    """Why ``board`` cannot be the board these views show, or "" (one line, for the caller to refuse
    the set with). Two kinds of evidence:

    * views showing a grid of more corners than ``board`` (each refused on its own): when at least
      LARGER_MIN_VIEWS of them, and LARGER_MIN_SHARE of the views with a grid, the board is larger
      (a 10x7 board under --board 9x7: 16 of 20 views refused as 10x7); the line names the largest
      size found (larger_problem);
    * for a plain checkerboard, the labels themselves (anchoring_problem): a partial view is placed
      on the board by the one edge it sees, so views placed from opposite edges name the same
      corners only if the board has exactly W (or H) corners there; when no view shows the board's
      border at both ends of that axis, nothing says it has, and the set is refused as ambiguous
      (the larger board never seen whole)."""
    return larger_problem(results, board) or anchoring_problem(results, board)


def _larger_sizes(results: Sequence[FileDetection]) -> tuple[list[tuple[int, int]], int]:
    """(sizes of the grids refused as larger than --board, views with a grid)."""
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
    return sizes, with_grid


def suggested_board(sizes: Sequence[tuple[int, int]], board: tuple[int, int]) -> tuple[int, int]:
    """The smallest board, in --board's orientation, that holds ``board`` and every grid in ``sizes``
    (each (longer, shorter) side, as the detector reports it: a partial 10x4 under 9x7 says 10x7)."""
    W, H = board
    long_, short = max(W, H), min(W, H)
    for a, b in sizes:
        long_, short = max(long_, a), max(short, b)
    return (long_, short) if W >= H else (short, long_)


def larger_problem(results: Sequence[FileDetection], board: tuple[int, int]) -> str:
    """The first kind of evidence (board_size_problem): enough views refused as larger, or ""."""
    W, H = board
    sizes, with_grid = _larger_sizes(results)
    if len(sizes) < LARGER_MIN_VIEWS or len(sizes) < LARGER_MIN_SHARE * max(with_grid, 1):
        return ""
    big = max(sizes, key=lambda s: s[0] * s[1])
    sw, sh = suggested_board(sizes, board)
    return (f"{len(sizes)} of {with_grid} views show a grid of corners larger than the --board {W}x{H} (up to "
            f"{big[0]}x{big[1]}): give the board's inner corners, e.g. --board {sw}x{sh}")


_AXES = (("across", "left", "right"), ("down", "top", "bottom"))


def placement(det: Detection, axis: int) -> str:
    """Where the labels of one view lie along ``axis`` (0: i across, 1: j down) of its W x H board:
    "span" (the first and the last line both labelled), "low" (the first only: the view was placed
    by the board's left (top) edge), "high" (the last only), or "" (neither: nothing placed it)."""
    W, H = det.board
    seen = np.isfinite(det.corners[:, 0]).reshape(H, W)
    lines = np.flatnonzero(seen.any(axis=0) if axis == 0 else seen.any(axis=1))
    if not lines.size:
        return ""
    n = W if axis == 0 else H
    first, last = lines[0] == 0, lines[-1] == n - 1
    return "span" if first and last else "low" if first else "high" if last else ""


def edges_seen(r: FileDetection, axis: int) -> tuple[bool, bool]:
    """Whether the image of ``r`` shows the board ending just past the first and just past the last
    line its labels span along ``axis`` (grid.board_edge_seen on the detector's contrast image, the
    test the anchoring uses). A file that no longer reads: (False, False)."""
    from .detector import find_lattice
    from .grid import board_edge_seen
    try:
        img = load_image(r.path)
    except ImageError:
        return False, False
    lat, _ = find_lattice(img, r.detection.board)
    if lat is None:
        return False, False
    W, _ = r.detection.board
    k = np.flatnonzero(np.isfinite(r.detection.corners[:, 0]))
    xy, ij = r.detection.corners[k], np.stack([k % W, k // W], axis=1)
    return board_edge_seen(lat.g, xy, ij, axis, 0), board_edge_seen(lat.g, xy, ij, axis, 1)


def placed_by(views: Sequence[FileDetection], axis: int) -> tuple[int, int, int] | None:
    """How the ``views`` were placed along ``axis``: None when one of them spans it with the board's
    border seen at both ends (the board has exactly that many lines; the spanning views are tried
    most corners first, so a set with a whole view costs one look); else (views placed by the first
    edge, by the last, spanning views), a spanning view counting for the one edge its image shows
    (a 10x7 board under --board 9x7 seen from its right edge with 9 columns in the image is labelled
    0-8, one column off a view from its left edge, and spans the 9x7 board as well)."""
    where = [placement(r.detection, axis) for r in views]
    n_lo, n_hi = where.count("low"), where.count("high")
    spans = sorted((r for r, w in zip(views, where) if w == "span"), key=lambda r: -r.detection.found)
    for r in spans:
        lo, hi = edges_seen(r, axis)
        if lo and hi:
            return None
        n_lo, n_hi = n_lo + (lo and not hi), n_hi + (hi and not lo)
    return n_lo, n_hi, len(spans)


def anchoring_problem(results: Sequence[FileDetection], board: tuple[int, int]) -> str:
    """The second kind of evidence (board_size_problem), for a plain checkerboard: along an axis with
    views placed by its first edge and views placed by its last (placed_by), and no view that shows
    both, the set is ambiguous; otherwise "". The line counts the views placed by each edge, names
    the grids found larger than --board (fewer than larger_problem needs) and suggests the size they
    point at, or asks for a view of the whole board."""
    views = [r for r in results if r.detection is not None and r.detection.detected
             and r.target == "checkerboard"]
    W, H = board
    for axis, (way, lo_edge, hi_edge) in enumerate(_AXES):
        counts = placed_by(views, axis)
        if counts is None or not (counts[0] and counts[1]):
            continue
        n_lo, n_hi, n_span = counts
        n = W if axis == 0 else H
        line = (f"ambiguous labels: {n_lo} view(s) placed by the board's {lo_edge} edge and {n_hi} by its "
                f"{hi_edge} edge name the same corners only if the board has exactly {n} inner corners {way}, "
                f"and no view shows both edges ({n_span} with all {n}, none with the border past both ends)")
        sizes, _ = _larger_sizes(results)
        if not sizes:
            return (f"{line}: check --board, or add a view that shows the whole board {way} (its {lo_edge} and "
                    f"{hi_edge} edges)")
        big = max(sizes, key=lambda s: s[0] * s[1])
        sw, sh = suggested_board(sizes, board)
        return (f"{line}; {len(sizes)} view(s) show a grid of corners larger than {W}x{H} (up to "
                f"{big[0]}x{big[1]}): the board is larger: give its inner corners, e.g. --board {sw}x{sh}")
    return ""
