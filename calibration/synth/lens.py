"""The lens synthetic images are rendered through: an mrcal LENSMODEL_OPENCV8 close to the nominal
Boson 640 with its 4.9 mm / 95 deg lens, built from the rig description.

Why OPENCV8: mrcal can represent it exactly (so truth.cameramodel *is* the lens used; the lens is an
``mrcal.cameramodel``, the project's one camera value), OpenCV and ROS
know it (``rational_polynomial``), and its rational radial term bends a 95 deg field into 640 px.

How it is made (nothing here is a measured number):

- focal length f = focal_length_mm / pixel_pitch_um (``Rig.focal_px``), from the rig description;
- a radial profile r(theta) = f theta (1 + a theta^2), a fisheye between equidistant and equisolid,
  with ``a`` chosen so that the half-width of the image (W/2 px) sits at half the HFoV of the rig
  description; fitted by linear least squares with the rational OPENCV8 radial terms k1..k6
  (calibration/lens/radial.py);
- small, fixed imperfections a real lens has: fy 0.1% shorter than fx, a principal point off the
  centre by a few pixels. Tangential terms stay 0 so that unprojection is a 1-D radial inversion
  (fast and exact: see :func:`unproject_radial`); a ``lens`` given by the caller may have any terms.
"""
from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from platform_tools.rig.cameras import camera_model

from calibration.lens.radial import FIT_MARGIN, rational_factor, rational_terms

from .truth_lens import RadialLens

# fixed imperfections of the synthetic lens (pixels / ratios); see the module docstring
FY_OVER_FX = 0.999
PRINCIPAL_OFFSET_PX = (2.3, -1.7)


def as_cameramodel(lens):
    """An ``mrcal.cameramodel`` (the project's one camera value) from a cameramodel (returned as is), a
    .cameramodel path, or a (lensmodel, intrinsics, imagersize (W, H)) tuple; a truth lens of another
    family (:class:`~calibration.synth.truth_lens.RadialLens`) is returned as is."""
    import mrcal
    if isinstance(lens, (mrcal.cameramodel, RadialLens)):
        return lens
    if isinstance(lens, (str, bytes)) or hasattr(lens, "__fspath__"):
        return mrcal.cameramodel(str(lens))
    lm, intr, size = lens
    return camera_model(str(lm), intr, (int(size[0]), int(size[1])))


def project(p: np.ndarray, lens) -> np.ndarray:
    """Pixels (..., 2) of camera-frame points ``p`` (..., 3) through ``lens`` (an mrcal.cameramodel, or a
    RadialLens: its own closed form)."""
    if isinstance(lens, RadialLens):
        return lens.project(p)
    import mrcal
    return mrcal.project(np.ascontiguousarray(p, dtype=float), *lens.intrinsics())


def _radial_profile_coefficient(f: float, half_width_px: float, half_hfov_rad: float) -> float:
    """``a`` in r = f theta (1 + a theta^2) so that r(half HFoV) = half width."""
    return (half_width_px / (f * half_hfov_rad) - 1.0) / half_hfov_rad ** 2


def fit_opencv8(f: float, width: int, height: int, hfov_deg: float) -> tuple[float, ...]:
    """OPENCV8 intrinsics (fx fy cx cy k1 k2 p1 p2 k3 k4 k5 k6) of the fisheye profile described in
    the module docstring. Raises ValueError if the fit is not monotonic over the image."""
    half_h = math.radians(hfov_deg) / 2.0
    a = _radial_profile_coefficient(f, width / 2.0, half_h)
    # angle of the image corner under the profile (Newton on f th (1 + a th^2) = corner radius)
    r_corner = math.hypot(width / 2.0, height / 2.0) / f
    th = r_corner
    for _ in range(50):
        th -= (th * (1 + a * th * th) - r_corner) / (1 + 3 * a * th * th)
    th_max = min(th * FIT_MARGIN, math.radians(85.0))
    theta = np.linspace(1e-4, th_max, 400)
    ru = np.tan(theta)
    rd = theta * (1 + a * theta ** 2)
    r2 = ru ** 2
    k = rational_terms(theta, rd)
    fx, fy = f, f * FY_OVER_FX
    cx = (width - 1) / 2.0 + PRINCIPAL_OFFSET_PX[0]
    cy = (height - 1) / 2.0 + PRINCIPAL_OFFSET_PX[1]
    intr = (fx, fy, cx, cy, *k)
    rr = ru * rational_factor(k, r2)
    if np.any(np.diff(rr) <= 0) or np.max(np.abs(rr - rd)) * f > 0.5:
        raise ValueError(f"cannot fit an OPENCV8 lens to f={f:.1f} px, HFoV={hfov_deg} deg, {width}x{height}")
    return tuple(float(x) for x in intr)


def nominal_thermal_lens(rig, camera: str = "thermal_left"):
    """The synthetic lens of a camera of the rig (``thermal_left`` / ``thermal_right``): an
    ``mrcal.cameramodel`` (OPENCV8, the rig's imager size, identity pose)."""
    frames = rig.sensor_frames()
    name = camera if camera.endswith("_optical") else f"{camera}_optical"
    if name not in frames or frames[name].camera_model is None:
        cams = [n.removesuffix("_optical") for n, fr in frames.items() if fr.optical]
        raise KeyError(f"no camera {camera!r} in the rig; cameras: {', '.join(cams)}")
    spec = rig.camera_model(frames[name].camera_model)
    intr = _fit_cached(rig.focal_px(spec), spec.width_px, spec.height_px, spec.hfov_deg.value)
    return camera_model("LENSMODEL_OPENCV8", intr, (spec.width_px, spec.height_px))


@lru_cache(maxsize=8)
def _fit_cached(f: float, w: int, h: int, hfov: float) -> tuple[float, ...]:
    return fit_opencv8(f, w, h, hfov)


# ----------------------------------------------------------------------------- unprojection
def _is_radial_opencv8(lens) -> bool:
    lm, intr = lens.intrinsics()
    return lm == "LENSMODEL_OPENCV8" and intr[6] == 0.0 and intr[7] == 0.0


def unproject_radial(q: np.ndarray, lens) -> np.ndarray:
    """Unit observation vectors of pixels ``q`` (..., 2) through a radial-only OPENCV8 lens (an
    mrcal.cameramodel).

    1-D Newton on r_d = r_u g(r_u^2) from a table start: converges to machine precision in a few
    steps, ~20x faster than the general 2-D solve (tests check it against mrcal.unproject)."""
    intr = lens.intrinsics()[1]
    fx, fy, cx, cy = (float(v) for v in intr[:4])
    k = np.array(intr[4:12])
    x = (q[..., 0] - cx) / fx
    y = (q[..., 1] - cy) / fy
    rd = np.hypot(x, y)
    # table of the monotonic branch r_u -> r_d, to start Newton
    ru_tab = np.tan(np.linspace(0.0, math.radians(89.0), 4000))
    rd_tab = ru_tab * rational_factor(k, ru_tab ** 2)
    stop = np.argmax(np.diff(rd_tab) <= 0) if np.any(np.diff(rd_tab) <= 0) else len(rd_tab) - 1
    ru = np.interp(rd, rd_tab[:stop + 1], ru_tab[:stop + 1])
    for _ in range(4):
        r2 = ru * ru
        num = 1 + k[0] * r2 + k[1] * r2 ** 2 + k[4] * r2 ** 3
        den = 1 + k[5] * r2 + k[6] * r2 ** 2 + k[7] * r2 ** 3
        dnum = 2 * ru * (k[0] + 2 * k[1] * r2 + 3 * k[4] * r2 ** 2)
        dden = 2 * ru * (k[5] + 2 * k[6] * r2 + 3 * k[7] * r2 ** 2)
        fval = ru * num / den - rd
        dval = num / den + ru * (dnum * den - num * dden) / den ** 2
        ru = ru - fval / dval
    scale = np.where(rd > 1e-15, ru / np.where(rd > 1e-15, rd, 1.0), 1.0)
    v = np.stack([x * scale, y * scale, np.ones_like(x)], axis=-1)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def unproject(q: np.ndarray, lens) -> np.ndarray:
    """Unit observation vectors (..., 3) of pixels (..., 2) through ``lens`` (an mrcal.cameramodel): the
    fast exact path when the lens allows it, a RadialLens' own inversion, else mrcal.unproject."""
    if isinstance(lens, RadialLens):
        return lens.unproject(q)
    if _is_radial_opencv8(lens):
        return unproject_radial(q, lens)
    import mrcal
    v = mrcal.unproject(np.ascontiguousarray(q, dtype=float), *lens.intrinsics())
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def max_valid_angle_rad(lens) -> float:
    """Off-axis angle where the lens' radial profile stops being monotonic (beyond it a projection is
    not the lens any more); 85 deg for lenses without a turning point in view."""
    if isinstance(lens, RadialLens):
        return lens.max_angle_rad
    lm, intr = lens.intrinsics()
    if lm != "LENSMODEL_OPENCV8":
        return math.radians(85.0)
    k = np.array(intr[4:12])
    th = np.linspace(0.0, math.radians(85.0), 4000)
    ru = np.tan(th)
    rd = ru * rational_factor(k, ru ** 2)
    bad = np.diff(rd) <= 0
    return float(th[np.argmax(bad)]) if np.any(bad) else math.radians(85.0)
