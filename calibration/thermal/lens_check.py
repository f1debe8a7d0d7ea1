"""Whether a solved lens, and every file it is exported to, holds over the whole image (no pole, no fold,
unproject -> project exact: calibration/lens/health.py), as verdict reasons.

The angle out to which a model must stay radially monotonic is the widest of: the angle the model
itself sees the image corners at, the widest board corner the solve placed (the data), and the
nominal lens of the rig description (a model whose pole sits at 52 deg while the nominal 95 deg lens
sees its corners at 58 deg maps the corner pixels onto rays 52 deg off-axis: its own view of the
corners cannot tell; the data and the nominal lens can).
"""
from __future__ import annotations

import numpy as np

from calibration.formats import readback
from calibration.intrinsics.mrcal_solver import Solution
from calibration.lens import health, kannala_brandt as kb


def observed_angle_deg(solution: Solution) -> float:
    """The widest off-axis angle (deg) of an inlier board corner: through the solved board poses (mrcal),
    or the lens's unprojection of the observed corners (OpenCV's fisheye, which keeps no poses here)."""
    obs = solution.observations
    m = solution.inlier
    if not m.any():
        return 0.0
    if solution.lensmodel == kb.NAME or not solution.optimization_inputs:
        v = kb.unproject(obs.corners[m], solution.intrinsics)
    else:
        import mrcal
        oi = solution.optimization_inputs
        frames = oi["frames_rt_toref"][oi["indices_frame_camintrinsics_camextrinsics"][:, 0]]
        pts = obs.board_points_m()
        v = np.concatenate([mrcal.transform_point_rt(frames[i], pts[m[i]]) for i in range(obs.n) if m[i].any()])
    ang = health.off_axis_deg(v)
    return float(np.nanmax(ang)) if np.isfinite(ang).any() else 0.0


def solution_health(solution: Solution, *, min_corner_angle_deg: float = 0.0) -> health.LensHealth:
    """The solved lens itself (before any export)."""
    need = max(min_corner_angle_deg, observed_angle_deg(solution))
    if solution.lensmodel == kb.NAME:
        p = solution.intrinsics
        return health.check(lambda v: kb.project(v, p), lambda q: kb.unproject(q, p), solution.imagersize,
                            (float(p[2]), float(p[3])), min_corner_angle_deg=need)
    return health.check_mrcal(solution.lensmodel, solution.intrinsics, solution.imagersize,
                              min_corner_angle_deg=need)


def exported_health(files: dict[str, str], solution: Solution, *,
                    min_corner_angle_deg: float = 0.0) -> dict[str, health.LensHealth]:
    """Every lens file among ``files`` read back by its own tools (formats/readback.py) and checked."""
    need = max(min_corner_angle_deg, observed_angle_deg(solution))
    return readback.check_files(files, solution.imagersize, min_corner_angle_deg=need)


def problems(checks: dict[str, health.LensHealth]) -> list[str]:
    """One verdict reason per file that fails, naming the file."""
    return [f"{name}: {h.problem()}; do not use it (take images reaching the image corners, or try "
            f"--lens-model splined or --solver opencv)" for name, h in checks.items() if not h.ok]
