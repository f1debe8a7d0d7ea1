"""From a solved lens to the distortion models other tools know, exactly where possible.

A solved lens is an ``mrcal.cameramodel`` (the project's one camera value) or, for OpenCV's Kannala-Brandt
fisheye that mrcal cannot hold, a :class:`~calibration.lens.kannala_brandt.KannalaBrandt`.
Target families and their names in each tool:

- ``plumb_bob`` (ROS) = OpenCV k1 k2 p1 p2 k3 = mrcal OPENCV4 / OPENCV5 (exact);
- ``rational_polynomial`` (ROS) = OpenCV's 8-term rational model = mrcal OPENCV8 (exact);
- ``equidistant`` (ROS) = cv2.fisheye = Kalibr ``pinhole-equi`` = Kannala-Brandt (exact for the
  OpenCV solver's result).

Anything else (a splined model; OPENCV8 for Kalibr, which has no rational model) is fitted: the
nearest model of the target family over the whole imager, with its RMS and worst pixel error.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from platform_tools.rig.cameras import imagersize

from calibration.lens import kannala_brandt as kb
from calibration.lens.fit import LensFit, fit_lensmodel, mrcal_unprojector


def unprojector(lens):
    """(..., 2) pixels -> (..., 3) unit rays of ``lens``: an mrcal.cameramodel or a
    :class:`~calibration.lens.kannala_brandt.KannalaBrandt`."""
    lensmodel, params = lens.intrinsics()
    if lensmodel == kb.NAME:
        return lambda q: kb.unproject(q, params)
    return mrcal_unprojector(lensmodel, params)


def projector(lens):
    """(..., 3) rays -> (..., 2) pixels of ``lens`` (as :func:`unprojector`)."""
    return lens_projector(*lens.intrinsics())


def lens_projector(lensmodel: str, params: np.ndarray):
    """(..., 3) rays -> (..., 2) pixels of the lens ``lensmodel`` (mrcal's name, or Kannala-Brandt's) with
    intrinsics ``params``."""
    params = np.asarray(params, dtype=float)
    if lensmodel == kb.NAME:
        return lambda v: kb.project(np.asarray(v, dtype=float), params)
    import mrcal
    return lambda v: mrcal.project(np.ascontiguousarray(v, dtype=float), lensmodel, params)


@dataclass(frozen=True)
class Representation:
    family: str                    # plumb_bob | rational_polynomial | equidistant
    K: np.ndarray                  # 3x3 camera matrix
    D: np.ndarray                  # distortion coefficients in the family's order
    fit: LensFit | None            # None when exact
    source_lensmodel: str

    @property
    def exact(self) -> bool:
        return self.fit is None

    def note(self) -> str:
        if self.exact:
            return f"exact: {self.source_lensmodel} is {self.family}"
        return (f"{self.source_lensmodel} has no {self.family} equivalent: nearest {self.family} fitted over "
                f"the whole image, RMS {self.fit.rms_px:.3f} px, worst {self.fit.max_px:.3f} px")

    def summary(self) -> dict:
        return dict(family=self.family, exact=self.exact,
                    fit_rms_px=None if self.exact else self.fit.rms_px,
                    fit_max_px=None if self.exact else self.fit.max_px, note=self.note())


def _K(p: np.ndarray) -> np.ndarray:
    return np.array([[p[0], 0.0, p[2]], [0.0, p[1], p[3]], [0.0, 0.0, 1.0]])


def _exact(lens, family: str) -> Representation | None:
    lm, p = lens.intrinsics()
    p = np.asarray(p, dtype=float)
    if family == "equidistant" and lm == kb.NAME:
        return Representation(family, _K(p), p[4:8].copy(), None, lm)
    if family == "plumb_bob" and lm in ("LENSMODEL_OPENCV4", "LENSMODEL_OPENCV5", "LENSMODEL_PINHOLE"):
        d = np.zeros(5)
        d[:len(p) - 4] = p[4:]
        return Representation(family, _K(p), d, None, lm)
    if family == "rational_polynomial" and lm in ("LENSMODEL_OPENCV4", "LENSMODEL_OPENCV5",
                                                   "LENSMODEL_OPENCV8", "LENSMODEL_PINHOLE"):
        d = np.zeros(8)
        d[:len(p) - 4] = p[4:]
        return Representation(family, _K(p), d, None, lm)
    return None


def representation(lens, family: str) -> Representation:
    """``lens`` (an mrcal.cameramodel, or a KannalaBrandt) in ``family``: exact if it is one, else the
    nearest fit over the whole imager."""
    exact = _exact(lens, family)
    if exact is not None:
        return exact
    src = unprojector(lens)
    lensmodel, params = lens.intrinsics()
    core = np.asarray(params, dtype=float)[:4]
    size = imagersize(lens)
    if family == "equidistant":
        f = kb.fit(src, size, core)
        return Representation(family, _K(f.intrinsics), f.intrinsics[4:8], f, lensmodel)
    target = {"rational_polynomial": "LENSMODEL_OPENCV8", "plumb_bob": "LENSMODEL_OPENCV5"}[family]
    f = fit_lensmodel(src, size, target, core)
    if target == "LENSMODEL_OPENCV8":
        f = _without_pole(f, src, size, core)
    return Representation(family, _K(f.intrinsics), f.intrinsics[4:], f, lensmodel)


#: denser grids the nearest OPENCV8 is fitted on again when the first fit is not healthy (fit.fit_lensmodel's default
#: grid is 40 points wide)
REFIT_GRID_WIDTHS = (80, 160)


def _without_pole(f, src, size, core):
    """``f`` (a nearest-OPENCV8 fit) if it is healthy (calibration.lens.health: every pixel survives unproject ->
    project, the radius grows out to the corners), else the first healthy fit on a denser grid, else ``f``. The
    rational fit is ill-conditioned: numerator and denominator may share a near root that falls between the grid's
    points, a pole the fit never sees (seen on a Kannala-Brandt solve: k1 -39.1 against k4 -38.7, no ray in a ring
    65 px from the centre, while the same lens to nine digits fitted healthy); a denser grid samples that ring."""
    from calibration.lens.health import check_mrcal
    if check_mrcal(f.lensmodel, f.intrinsics, size).ok:
        return f
    for n_width in REFIT_GRID_WIDTHS:
        g = fit_lensmodel(src, size, f.lensmodel, core, n_width=n_width)
        if check_mrcal(g.lensmodel, g.intrinsics, size).ok:
            return g
    return f


# Beyond this off-axis angle at the image corners a lens is a fisheye for ROS: image_geometry unprojects a
# plumb_bob / rational_polynomial camera with cv::undistortPoints' default 5 iterations, which leaves a
# healthy 95 deg rational lens (corners at 58 deg) 3.2 px wrong in the image corners (measured on the
# synthetic lens, tests/calibration/test_formats.py), while its equidistant path inverts exactly.
ROS_FISHEYE_CORNER_DEG = 45.0


def corner_angle_deg(lens) -> float:
    """The largest off-axis angle (deg) at which ``lens`` sees one of the imager's four corner pixels."""
    from calibration.lens.health import off_axis_deg
    w, h = imagersize(lens)
    q = np.array([[0.0, 0.0], [w - 1.0, 0.0], [0.0, h - 1.0], [w - 1.0, h - 1.0]])
    return float(np.nanmax(off_axis_deg(unprojector(lens)(q))))


def exact_or_nearest(lens) -> Representation:
    """The lens in the OpenCV model it is (OPENCV4/5 -> plumb_bob, OPENCV8 -> rational_polynomial,
    Kannala-Brandt -> equidistant), else the better of the rational_polynomial and equidistant fits."""
    for family in ("plumb_bob", "rational_polynomial", "equidistant"):
        exact = _exact(lens, family)
        if exact is not None:
            return exact
    fits = [representation(lens, f) for f in ("rational_polynomial", "equidistant")]
    return min(fits, key=lambda r: r.fit.rms_px)


def nearest_for_ros(lens) -> Representation:
    """The ROS distortion model for the lens: ``equidistant`` (exact for Kannala-Brandt, fitted else) for a
    lens wider than ROS_FISHEYE_CORNER_DEG at the image corners (the Boson's 95 deg lens), else
    :func:`exact_or_nearest`."""
    if corner_angle_deg(lens) > ROS_FISHEYE_CORNER_DEG:
        return representation(lens, "equidistant")
    return exact_or_nearest(lens)


def nearest_kalibr(lens) -> Representation:
    """Kalibr's pinhole cameras know radtan (= plumb_bob without k3) and equidistant; for a fisheye
    the equidistant (pinhole-equi) model is the one to use: exact for Kannala-Brandt, fitted else."""
    return representation(lens, "equidistant")
