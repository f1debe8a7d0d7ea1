"""Corner observations made by projecting a board through a known lens (no images).

The solver's own test bench: a board placed at random poses across the imager (near the corners,
partly outside, tilted), projected with mrcal.project, plus Gaussian pixel noise. With no detector in
the loop, what comes back from a solve measures the solver alone.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from calibration.lens.fit import fit_lensmodel
from .observations import BoardObservations


@dataclass(frozen=True)
class SyntheticCorners:
    observations: BoardObservations
    lensmodel: str
    intrinsics: np.ndarray
    rt_cam_board: np.ndarray      # (N, 6) true board poses


def fisheye_truth(focal_px: float, imagersize: tuple[int, int], *, lensmodel: str = "LENSMODEL_OPENCV8",
                  centre_offset_px: tuple[float, float] = (3.0, -2.0)) -> tuple[str, np.ndarray]:
    """A fisheye-like lens in ``lensmodel``: the best fit to an equidistant projection r = f theta
    with the given focal length and a principal point slightly off the imager centre."""
    import mrcal
    w, h = imagersize
    c = np.array([(w - 1) / 2 + centre_offset_px[0], (h - 1) / 2 + centre_offset_px[1]])

    def unproject(q: np.ndarray) -> np.ndarray:
        d = (q - c) / focal_px
        th = np.linalg.norm(d, axis=-1, keepdims=True)
        s = np.where(th > 1e-12, np.sin(th) / np.where(th > 1e-12, th, 1), 1.0)
        return np.concatenate([d * s, np.cos(th)], axis=-1)

    seed = np.array([focal_px, focal_px, c[0], c[1]])
    return lensmodel, fit_lensmodel(unproject, imagersize, lensmodel, seed).intrinsics


def _rotation_facing(ray: np.ndarray, tilt_deg: float, rng: np.random.Generator) -> np.ndarray:
    """A board orientation (Rodrigues) whose normal is the ray direction, tilted by up to tilt_deg."""
    import mrcal
    z = ray / np.linalg.norm(ray)
    x = np.cross([0.0, 1.0, 0.0], z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    R = np.column_stack([x, y, z])
    tilt = mrcal.R_from_r(np.radians(rng.uniform(-tilt_deg, tilt_deg, 3)))
    return mrcal.r_from_R(R @ tilt)


def simulate(lensmodel, intrinsics: np.ndarray | None, imagersize: tuple[int, int], *,
             board: tuple[int, int] = (10, 7), square_m: float = 0.04, n: int = 30,
             noise_px: float = 0.05, seed: int = 0, region: str = "full",
             distance_m: tuple[float, float] = (0.35, 0.9), tilt_deg: float = 40.0,
             min_corners: int = 12) -> SyntheticCorners:
    """``n`` board observations. ``region``: 'full' places board centres all over the imager (up
    to its edges, so many boards are partial); 'centre' keeps them in the middle 30%.
    ``lensmodel``: an mrcal lens-model name (with ``intrinsics``), or any lens object with
    ``project(points)`` and ``unproject(pixels)`` methods (e.g. a truth lens of another family,
    calibration/synth/truth_lens.py; ``intrinsics`` None), so corners need not come from mrcal's models."""
    import mrcal
    if isinstance(lensmodel, str):
        def project(p):
            return mrcal.project(p, lensmodel, intrinsics)

        def unproject(q):
            return mrcal.unproject(q, lensmodel, intrinsics, normalize=True)
    else:
        lens = lensmodel
        project, unproject = lens.project, lens.unproject
        lensmodel, intrinsics = lens.intrinsics()
    rng = np.random.default_rng(seed)
    w, h = imagersize
    bw, bh = board
    obj = np.zeros((bh, bw, 3))
    obj[..., 0], obj[..., 1] = np.meshgrid(np.arange(bw) * square_m, np.arange(bh) * square_m)
    obj = obj.reshape(-1, 3)
    centre_obj = obj.mean(axis=0)

    names, corners, poses = [], [], []
    tries = 0
    while len(names) < n:
        tries += 1
        if tries > 50 * n:
            raise RuntimeError("could not place enough boards in view")
        if region == "centre":
            q = np.array([rng.uniform(0.35, 0.65) * w, rng.uniform(0.35, 0.65) * h])
        else:
            q = np.array([rng.uniform(0.0, 1.0) * w, rng.uniform(0.0, 1.0) * h])
        ray = unproject(q)
        r = _rotation_facing(ray, tilt_deg, rng)
        t = ray * rng.uniform(*distance_m) - mrcal.rotate_point_r(r, centre_obj)
        rt = np.concatenate([r, t])
        pcam = mrcal.transform_point_rt(rt, obj)
        if (pcam[:, 2] <= 0.05).any():
            continue
        qc = project(pcam)
        qc = qc + rng.normal(0.0, noise_px, qc.shape)
        inside = (qc[:, 0] >= 0) & (qc[:, 0] <= w - 1) & (qc[:, 1] >= 0) & (qc[:, 1] <= h - 1)
        if region == "centre" and not inside.all():
            continue
        if inside.sum() < min_corners:
            continue
        qc[~inside] = np.nan
        names.append(f"{len(names):03d}.png")
        corners.append(qc)
        poses.append(rt)
    obs = BoardObservations(names, np.array(corners), np.ones((n, bw * bh)), board, square_m, imagersize)
    return SyntheticCorners(obs, lensmodel, np.asarray(intrinsics, dtype=float), np.array(poses))
