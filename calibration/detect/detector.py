"""detect_corners(image, board=(W, H)): the heated-checkerboard detector, end to end."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from .candidates import column_pattern, find_candidates
from .complete import complete, corners_past
from .grid import anchor, label, link, orient
from .grow import grow, lattice_outliers
from .refine import image_noise, levels, refine
from .regions import disagreeing

MIN_CORNERS = 6


@dataclass(frozen=True)
class Detection:
    """One image's board: ``corners`` (H*W, 2) in grid order (row j, then column i; top-left first),
    NaN where a corner was not found; ``level`` (H*W,) mrcal's level (0 best, -1 not found);
    ``weight`` = 2^-level (0 where not found)."""
    board: tuple[int, int]
    corners: np.ndarray
    level: np.ndarray
    reason: str = ""
    candidates: int = 0
    extra: dict = field(default_factory=dict)

    @property
    def found(self) -> int:
        return int(np.sum(np.isfinite(self.corners[:, 0])))

    @property
    def detected(self) -> bool:
        return self.found > 0

    @property
    def complete(self) -> bool:
        return self.found == self.board[0] * self.board[1]

    @property
    def weight(self) -> np.ndarray:
        return np.where(self.level >= 0, 2.0 ** (-self.level.astype(float)), 0.0)


def empty_detection(board, reason, n_cand=0) -> Detection:
    """No board in this image, and why."""
    n = board[0] * board[1]
    return Detection(board, np.full((n, 2), np.nan), -np.ones(n, int), reason, n_cand)


def to_float(image: np.ndarray) -> np.ndarray:
    img = np.asarray(image)
    if img.ndim == 3:
        img = img[..., :3].mean(axis=2) if img.shape[2] >= 3 else img[..., 0]
    if img.ndim != 2:
        raise ValueError(f"expected a single-channel image, got shape {img.shape}")
    return img.astype(np.float32)


OCCLUDER_RANGE = 2.0    # x the board's median: a corner's neighbourhood spanning more is touched


def touched(f: np.ndarray, xy: np.ndarray, spacing: np.ndarray) -> np.ndarray:
    """Corners that something much hotter or colder than the board touches (a hand over the board,
    a warm object at its rim): the intensity range within max(3, 0.25 x spacing) px exceeds
    OCCLUDER_RANGE x the median range over the board's corners (a blurred X-corner spans the board's
    hot-to-cold contrast, a hand several times that). The hand's edge against the squares can make
    a saddle that passes every other check, a few px from the covered corner (seed 200 hard 7x7
    035: reported 4.9 px off)."""
    ok = np.isfinite(xy[:, 0])
    out = np.zeros(len(xy), bool)
    if ok.sum() < MIN_CORNERS:
        return out
    g = cv2.blur(f, (3, 3))
    H, W = f.shape
    rng = np.full(len(xy), np.nan)
    for k in np.flatnonzero(ok):
        r = int(math.ceil(max(3.0, 0.25 * spacing[k])))
        x, y = int(round(xy[k, 0])), int(round(xy[k, 1]))
        win = g[max(y - r, 0):min(y + r + 1, H), max(x - r, 0):min(x + r + 1, W)]
        rng[k] = float(win.max() - win.min())
    return ok & (rng > OCCLUDER_RANGE * np.nanmedian(rng))


@dataclass(frozen=True)
class Lattice:
    """What every target's detector starts from: the destriped image ``f`` (and ``fine``, destriped
    only where the rows agree on the column pattern: what the sub-pixel refinement reads), the
    contrast-normalised smoothed image ``g``, the saddle response ``S``, the local contrast and pixel noise, and the
    labelled corner lattice (``xy`` (m, 2), ``ij`` (m, 2) lattice labels with an arbitrary origin and
    orientation)."""
    f: np.ndarray
    g: np.ndarray
    S: np.ndarray
    local_sd: np.ndarray
    noise: float
    n_candidates: int
    xy: np.ndarray
    ij: np.ndarray
    fine: np.ndarray | None = None     # the image the sub-pixel refinement runs on (normalise, measured_only)


def find_lattice(image: np.ndarray, board: tuple[int, int]) -> tuple[Lattice | None, str]:
    """Candidates, linked and labelled into the largest lattice, its labels made consistent
    (regions.py: what disagrees with the largest region is dropped), grown (never past max(W, H) + 1
    lattice steps); (None, why) when there is no grid of corners."""
    W, H = int(board[0]), int(board[1])
    raw = to_float(image)
    pattern, measured = column_pattern(raw)
    f = raw - pattern[None, :]                       # candidates.normalise, without a second pass
    if float(f.max() - f.min()) <= 0:
        return None, "the image is flat (every pixel the same)"
    noise = image_noise(f)
    cands, g, S, local_sd = find_candidates(f, noise=noise)
    if len(cands.xy) < MIN_CORNERS:
        none = np.zeros((0, 2))
        return Lattice(f, g, S, local_sd, noise, len(cands.xy), none, none.astype(int)), \
            "no checkerboard corners found"
    slots = link(cands)
    idx, ij = label(cands, slots)
    if len(idx) < MIN_CORNERS:
        return Lattice(f, g, S, local_sd, noise, len(cands.xy), cands.xy[:0], ij[:0]), "no grid of corners found"
    # one labelling: what a wrong link shifted is dropped (the growth finds it again from the grid)
    keep = ~disagreeing(cands.xy[idx], ij)[0]
    idx, ij = idx[keep], ij[keep]
    # fill the holes and extend the runs the linking missed
    xy, ij, _ = grow(g, S, cands.xy[idx], ij, cands.strength[idx], (W, H))
    keep = ~disagreeing(xy, ij)[0]
    xy, ij = xy[keep], ij[keep]
    fine = raw - np.where(measured, pattern, 0.0)[None, :].astype(np.float32)   # normalise(measured_only=True)
    lat = Lattice(f, g, S, local_sd, noise, len(cands.xy), xy, ij, fine)
    if len(xy) < MIN_CORNERS:
        return lat, "no grid of corners found"
    return lat, ""


def corner_spacing(xy: np.ndarray, ij: np.ndarray) -> np.ndarray:
    """Each corner's distance to its nearest labelled grid neighbour (8 px when it has none)."""
    pos = {tuple(k): p for k, p in zip(ij.tolist(), xy.tolist())}
    return np.array([min([math.sqrt((pos[n][0] - p[0]) ** 2 + (pos[n][1] - p[1]) ** 2) for n in
                          ((i + 1, j), (i - 1, j), (i, j + 1), (i, j - 1)) if n in pos] or [8.0])
                     for (i, j), p in zip(ij.tolist(), xy.tolist())])


def finish(lat: Lattice, xy: np.ndarray, ij: np.ndarray, board: tuple[int, int],
           absent: np.ndarray | None = None) -> Detection:
    """From a grid in board coordinates to the Detection: sub-pixel refinement, lattice and touch
    checks, completion of the missing board corners, mrcal levels. ``absent`` (H*W,) marks corners
    the target does not have (a marker's own squares): never reported, even if the image shows one."""
    W, H = board
    spacing = corner_spacing(xy, ij)
    fine = refine(lat.f if lat.fine is None else lat.fine, xy, spacing)
    fine[lattice_outliers(fine, ij)] = np.nan
    fine[touched(lat.f, fine, spacing)] = np.nan
    ok = np.isfinite(fine[:, 0])
    # board corners still missing (too faint for the growth, dropped by the refinement): predicted
    # from the anchored grid, kept where the image shows that corner (complete.py)
    fine, ij, _ = complete(lat.f, lat.S, fine[ok], ij[ok], (W, H), lat.noise)
    k = ij[:, 1] * W + ij[:, 0]
    if absent is not None:
        keep = ~absent[k]
        fine, k = fine[keep], k[keep]
    corners = np.full((W * H, 2), np.nan)
    lv = -np.ones(W * H, int)
    corners[k] = fine
    lv[k] = levels(lat.f, fine, lat.local_sd, lat.noise)
    return Detection((W, H), corners, lv, "", lat.n_candidates)


def check_board_size(W: int, H: int, minimum: int = 2) -> tuple[int, int]:
    W, H = int(W), int(H)
    if W < minimum or H < minimum:
        raise ValueError(f"board {W}x{H}: needs at least {minimum}x{minimum} inner corners")
    return W, H


def detect_corners(image: np.ndarray, board: tuple[int, int] = (10, 7)) -> Detection:
    """Find the W x H inner corners of a (heated) checkerboard in a thermal image (16-bit counts,
    8-bit, or float; one channel). Partial and occluded boards give the corners seen, at their board
    coordinates; corner (0, 0) is the top-left corner as seen in the image (see grid.py)."""
    W, H = check_board_size(*board)
    lat, why = find_lattice(image, (W, H))
    if why:
        return empty_detection((W, H), why, lat.n_candidates if lat is not None else 0)
    xy, ij, n_cand = lat.xy, lat.ij, lat.n_candidates
    ij, why = orient(xy, ij, W, H)
    if why:
        return empty_detection((W, H), why, n_cand)
    keep = ij[:, 0] >= 0
    xy, ij = xy[keep], ij[keep]
    if len(xy) < MIN_CORNERS:
        return empty_detection((W, H), "no grid of corners found", n_cand)
    ij = ij - ij.min(axis=0)
    if ij[:, 0].max() < 1 or ij[:, 1].max() < 1:
        return empty_detection((W, H), "only one row of corners found", n_cand)
    ij, why = anchor(lat.g, xy, ij, W, H, corners_go_on=lambda axis, end: shows_corners_past(lat, xy, ij, axis, end))
    if ij is None:
        return empty_detection((W, H), why, n_cand)
    why = goes_on_past_edge(lat, xy, ij, (W, H))
    if why:
        return empty_detection((W, H), why, n_cand)
    det = finish(lat, xy, ij, (W, H))
    shift = reanchor_shift(lat, det)
    if shift is None:
        return det
    # the completed grid reads its ends otherwise than the grown one did: placed again from what it shows,
    # and that placement must then hold on its own completion
    ij = ij + shift
    why = goes_on_past_edge(lat, xy, ij, (W, H))
    if why:
        return empty_detection((W, H), why, n_cand)
    det = finish(lat, xy, ij, (W, H))
    if reanchor_shift(lat, det) is not None:
        return empty_detection((W, H), "partial board: its placement on the board changes as its corners are "
                               "completed; cannot tell which corners they are", n_cand)
    return det


def reanchor_shift(lat: Lattice, det: Detection) -> np.ndarray | None:
    """The anchoring (grid.anchor) run again on a finished detection's own corners: the shift to add to every
    label where it places them elsewhere, else None (placed where they are, or nothing to place them by: the
    first placement then stands; refusing there lost 7 correctly labelled views of the 40-image calibration
    sets). The anchoring first reads the board's ends on the grown grid, before the completion adds the corners
    that were too faint to grow, so an end can be judged a line or more short of where the grid ends. A hand
    hiding the squares past that line makes it look like the board's border (stereographic hard seed 200,
    10x7 image 033: a cold board's faint first columns, its 54 corners labelled two columns off), while the
    completed grid shows the squares going on there and the border at the other end."""
    W, H = det.board
    ok = np.isfinite(det.corners[:, 0])
    k = np.nonzero(ok)[0]
    ij = np.stack([k % W, k // W], axis=1)
    xy = det.corners[ok]
    if len(k) < MIN_CORNERS or len(k) == W * H:
        return None
    low = ij.min(axis=0)
    rel = ij - low
    placed, _ = anchor(lat.g, xy, rel, W, H,
                       corners_go_on=lambda axis, end: shows_corners_past(lat, xy, rel, axis, end))
    if placed is None:
        return None
    shift = (placed - rel).min(axis=0) - low
    return shift if shift.any() else None


def shows_corners_past(lat: Lattice, xy: np.ndarray, ij: np.ndarray, axis: int, end: int) -> bool:
    """Whether the destriped image shows at least one corner of the grid (``ij`` labels starting at 0)
    on the lattice line just past its ``end`` (0 low, 1 high) along ``axis`` (complete.corners_past)."""
    line = -1 if end == 0 else int(ij[:, axis].max()) + 1
    return corners_past(lat.f, lat.S, xy, ij, axis, line, lat.noise)[0] > 0


PAST_EDGE_MAX = 1     # corners the destriped image shows on a line past the board's edge: at most this many


def goes_on_past_edge(lat: Lattice, xy: np.ndarray, ij: np.ndarray, board: tuple[int, int]) -> str:
    """Why the placed grid (``ij`` board coordinates) cannot be where it was placed, or "": on every
    lattice line just past an edge of the board the grid reaches, the image must show no corner of
    this grid (complete.corners_past). Where it shows more than PAST_EDGE_MAX, the board goes on
    there: the anchoring took a line for the board's edge that is not (stereographic hard seed 100,
    10x7 image 012: a hand over the squares past the third column found; 18 corners labelled four
    columns off), or the board is larger than --board and its extra corners were all missed."""
    W, H = board
    for axis, n_board in ((0, W), (1, H)):
        name = "i (across)" if axis == 0 else "j (down)"
        for line, at_edge in ((-1, ij[:, axis].min() == 0), (n_board, ij[:, axis].max() == n_board - 1)):
            if not at_edge:
                continue
            passed, judged = corners_past(lat.f, lat.S, xy, ij, axis, line, lat.noise)
            if passed > PAST_EDGE_MAX:
                side = "before the first" if line < 0 else "past the last"
                return (f"the image shows {passed} of {judged} corners {side} line along {name} where the "
                        f"{W}x{H} board should end: the board is larger than {W}x{H}, or a hand or the image "
                        f"edge hides part of it; cannot tell which corners these are")
    return ""
