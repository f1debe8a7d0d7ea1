"""The thermal intrinsics pipeline behind ``calibrate thermal``: images -> the board's corners in each
(and corners.vnl) -> a solved lens (mrcal, or OpenCV's fisheye) -> every output file and the verdict
(:mod:`.outputs`).

Bad input raises :class:`~platform_tools.rig.conventions.UserError` (exit 2) before anything is solved;
data that cannot be solved (no board found, too few images) raises
:class:`~platform_tools.rig.conventions.CheckFailed` (exit 1). Nothing here writes a file.
"""
from __future__ import annotations

import logging

from platform_tools.rig.conventions import CheckFailed, UserError

from calibration.intrinsics.observations import BoardObservations
from calibration.intrinsics.quiet import quiet_stderr
from calibration.thermal.outputs import Outputs, build

log = logging.getLogger("calibration.thermal")


def check_lens_model(lens_model: str | None, imagersize: tuple[int, int]) -> None:
    """A bad ``--lens-model`` name is bad input before any work is done (the field of view does not
    decide whether a name is valid: 100 deg stands in for it)."""
    if lens_model is None:
        return
    from calibration.intrinsics.lensmodels import LensModelError, resolve
    try:
        resolve(lens_model, imagersize, 100.0)
    except LensModelError as exc:
        raise UserError(str(exc)) from None


def detect(images: str, board: tuple[int, int], square_m: float,
           target: str = "checkerboard") -> tuple[BoardObservations, str]:
    """Detection over the images (a folder or a glob): (observations, corners.vnl text). Corrupt files
    are bad input; saturated or blank images are skipped and named (all of them unusable is bad input
    too). ``board``: inner corners (W, H); ``square_m``: the square size in metres."""
    from calibration.detect import ImageError, detect_files, list_images
    from calibration.detect.batch import board_size_problem
    from calibration.formats.corners_vnl import BoardCorners, format_corners
    from calibration.intrinsics.observations import from_detections
    try:
        files = list_images(images)
    except ImageError as exc:
        raise UserError(f"--images {exc}") from None
    results = detect_files(files, board, strict=False, target=target)
    bad = [r for r in results if r.detection is None]
    # ImageError reads "<path>: <what is wrong>"; judge the second part only
    what = {id(r): r.error[len(str(r.path)):] if r.error.startswith(str(r.path)) else r.error for r in bad}
    corrupt = [r for r in bad if "saturated" not in what[id(r)] and "same value" not in what[id(r)]]
    if corrupt:
        raise UserError(f"{corrupt[0].error}; remove it (and {len(corrupt) - 1} other such file(s))"
                        if len(corrupt) > 1 else f"{corrupt[0].error}; remove it or pass --images a glob "
                                                 f"that leaves it out")
    good = [r for r in results if r.detection is not None]
    if not good:
        raise UserError(f"--images {images}: none of the {len(results)} images is usable: {bad[0].error}")
    why = board_size_problem(good, board)
    if why:
        raise UserError(f"--images {images}: {why}; nothing written")
    for r in bad:
        log.warning("skipped %s", r.error)
    sizes = {r.imagersize for r in good}
    if len(sizes) > 1:
        raise UserError(f"--images {images}: images of different sizes {sorted(sizes)}; one camera at a time")
    imagersize = sizes.pop()
    names = [r.path.name for r in good]
    dets = [r.detection.corners if r.detection.detected else None for r in good]
    wts = [r.detection.weight for r in good]
    obs = from_detections(names, dets, board, square_m, imagersize, wts)
    obs.missed.extend(r.path.name for r in bad)
    obs.missed_why = _why_missed(good, bad)
    obs.bit_depth = _bit_depth([r.path for r in good])
    rows = [BoardCorners(r.path.name, r.detection.corners if r.detection.detected else None,
                         r.detection.level if r.detection.detected else None) for r in good]
    rows += [BoardCorners(r.path.name, None, None) for r in bad]
    if obs.n == 0:
        reasons = sorted({r.detection.reason for r in good if r.detection.reason})
        raise CheckFailed(f"--images {images}: no {board[0]}x{board[1]} board found in any of {len(results)} "
                          f"images ({'; '.join(reasons[:2]) or 'no detection'}); check --board (inner corners "
                          f"across x down) and that the board is warmer or cooler than the background")
    return obs, format_corners(rows)


def _why_missed(good, bad) -> list:
    """calibration/report/missed.py's cause for every image without a board."""
    from calibration.report.missed import classify
    out = [classify(r.path.name, r.detection.reason, r.detection.candidates) for r in good if not r.detection.detected]
    return out + [classify(r.path.name, r.error[len(str(r.path)) + 2:] if r.error.startswith(str(r.path)) else r.error)
                  for r in bad]


def _bit_depth(paths) -> int | None:
    """8 when any input image is 8-bit (an AGC'd stream: the report says what that costs), 16 when all
    are 16-bit, None when unknown."""
    import cv2
    depths = set()
    for p in paths:
        img = cv2.imread(str(p), cv2.IMREAD_UNCHANGED)
        if img is not None:
            depths.add(8 * img.dtype.itemsize)
    return min(depths) if depths else None


def solve(obs: BoardObservations, *, solver: str, lens_model: str | None, focal_px: float,
          nominal_corner_angle_deg: float = 0.0, circle_radius_m: float | None = None):
    """:func:`solve_once`, and for a circle grid (``circle_radius_m``: its discs' radius; None: not a
    circle grid, or the correction off) iterated with each disc's centroid bias taken off
    (calibration/intrinsics/circle_bias.py): the model the first solve chose (or was given) is solved
    again, warm, from the corrected centres until the correction stops changing."""
    from calibration.intrinsics import circle_bias
    first = solve_once(obs, solver=solver, lens_model=lens_model, focal_px=focal_px,
                       nominal_corner_angle_deg=nominal_corner_angle_deg)
    if circle_radius_m is None:
        return first
    try:
        return circle_bias.solve_corrected(obs, first, circle_radius_m)[0]
    except Exception as exc:      # noqa: BLE001 - mrcal, OpenCV raise plain errors on real data
        detail = " ".join(str(exc).split())[:160] or type(exc).__name__
        raise CheckFailed(f"the circle-centre correction's re-solve failed ({detail}); try "
                          f"--no-centroid-correction") from None


def solve_once(obs: BoardObservations, *, solver: str, lens_model: str | None, focal_px: float,
               nominal_corner_angle_deg: float = 0.0):
    """The lens from the observations: ``solver`` "mrcal" (``lens_model`` a name lensmodels.resolve
    accepts, None: chosen by the data, below) or "opencv" (cv2.fisheye); ``focal_px`` the nominal focal
    length, the seed. Returns an :class:`~calibration.intrinsics.mrcal_solver.Solution`.

    The default (``lens_model`` None, mrcal) is chosen by the data between OpenCV's Kannala-Brandt fisheye
    and mrcal's OPENCV8, or OPENCV5 in OPENCV8's place when OPENCV8 is unusable, solved from the same
    corners (calibration/thermal/lens_choice.py): a model with a pole or fold out to the image corners'
    angle (the widest of its own, the data's and ``nominal_corner_angle_deg``) or that does not
    round-trip over the whole image (thermal/lens_check.py) is out; between two healthy ones, the one
    that predicts held-out views better (calibration/intrinsics/model_choice.py: Kannala-Brandt unless
    the mrcal model is significantly better). The notes say which and why."""
    from calibration.intrinsics import SolveError, mrcal_solver, opencv_solver
    from calibration.intrinsics.lensmodels import LensModelError
    try:
        if solver == "opencv":
            if lens_model is not None:
                raise UserError("--lens-model applies to --solver mrcal only (OpenCV's fisheye is Kannala-Brandt)")
            return opencv_solver.solve(obs, focal_px=focal_px)
        solution = mrcal_solver.solve(obs, lensmodel=lens_model, focal_px=focal_px)
        if lens_model is not None:
            return solution
        return _choose(obs, solution, focal_px, nominal_corner_angle_deg)
    except LensModelError as exc:
        raise UserError(str(exc)) from None
    except SolveError as exc:
        raise CheckFailed(str(exc)) from None


def _choose(obs: BoardObservations, o8, focal_px: float, nominal_corner_angle_deg: float):
    """The default model (:func:`solve_once`): Kannala-Brandt solved from ``obs`` beside OPENCV8 (and
    OPENCV5 when OPENCV8 is unusable), then calibration/thermal/lens_choice.py keeps one. A candidate
    that cannot be solved is left out."""
    from calibration.intrinsics import SolveError, mrcal_solver, opencv_solver
    from calibration.thermal import lens_choice as lc
    try:
        kb = opencv_solver.solve(obs, focal_px=focal_px)
    except SolveError:
        kb = None

    def opencv5():
        try:
            return mrcal_solver.solve(obs, lensmodel=lc.MRCAL_NAMES[lc.OPENCV5], focal_px=focal_px)
        except Exception:      # noqa: BLE001 - mrcal raises plain errors on real data; OPENCV8 is solved
            return None

    def kb_held(n):
        try:
            return opencv_solver.solve(obs, focal_px=focal_px, fixed_terms=n)
        except SolveError:
            return None

    return lc.choose_default(o8, kb, opencv5, nominal_corner_angle_deg, kb_held)


def calibrate(images: str, board: tuple[int, int], square_m: float, *, solver: str, lens_model: str | None,
              focal_px: float, expected_size: tuple[int, int], camera_name: str, rig_hash: str,
              show_solver_output: bool = False, nominal_corner_angle_deg: float = 0.0,
              target: str = "checkerboard", circle_radius_m: float | None = None):
    """The whole pipeline: (the observations detected, the solution, its
    :class:`~calibration.thermal.outputs.Outputs`; the solution holds the observations it kept after
    rejecting images). ``expected_size``:
    the rig description's thermal imager (W, H) px, warned about when the images differ;
    ``show_solver_output``: let mrcal's C-level progress lines through to stderr;
    ``nominal_corner_angle_deg``: the angle the rig's nominal lens sees the image corners at (lens_check.py);
    ``target``: the --target kind (calibration/targets); ``circle_radius_m``: a circle grid's disc radius,
    whose centroid bias is then taken off in the solve (None: no correction)."""
    check_lens_model(lens_model, expected_size)
    obs, corners_text = detect(images, board, square_m, target)
    if obs.imagersize != tuple(expected_size):
        log.warning("images are %dx%d, the rig description's thermal camera is %dx%d (its nominal lens's "
                    "field is not used to check the model)", *obs.imagersize, *expected_size)
        nominal_corner_angle_deg = 0.0
    with quiet_stderr(enabled=not show_solver_output):
        solution = solve(obs, solver=solver, lens_model=lens_model, focal_px=focal_px,
                         nominal_corner_angle_deg=nominal_corner_angle_deg, circle_radius_m=circle_radius_m)
        out: Outputs = build(solution, camera_name=camera_name, rig_hash=rig_hash, corners_vnl=corners_text,
                             nominal_corner_angle_deg=nominal_corner_angle_deg)
    return obs, solution, out
