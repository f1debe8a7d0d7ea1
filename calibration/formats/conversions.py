"""From a solved lens to the distortion models other tools know, exactly where possible.

A solved lens is an mrcal model (``LENSMODEL_*`` + intrinsics) or OpenCV's Kannala-Brandt fisheye.
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

from ..intrinsics import kannala_brandt as kb
from ..intrinsics.lensfit import LensFit, fit_lensmodel, mrcal_unprojector


@dataclass(frozen=True)
class Lens:
    lensmodel: str                 # an mrcal LENSMODEL_* name, or kannala_brandt.NAME
    params: np.ndarray             # fx fy cx cy distortion...
    imagersize: tuple[int, int]

    def unprojector(self):
        if self.lensmodel == kb.NAME:
            return lambda q: kb.unproject(q, self.params)
        return mrcal_unprojector(self.lensmodel, self.params)

    def projector(self):
        if self.lensmodel == kb.NAME:
            return lambda v: kb.project(v, self.params)
        import mrcal
        return lambda v: mrcal.project(np.ascontiguousarray(v, dtype=float), self.lensmodel, self.params)


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


def _exact(lens: Lens, family: str) -> Representation | None:
    p = np.asarray(lens.params, dtype=float)
    lm = lens.lensmodel
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


def representation(lens: Lens, family: str) -> Representation:
    """``lens`` in ``family``: exact if it is one, else the nearest fit over the whole imager."""
    exact = _exact(lens, family)
    if exact is not None:
        return exact
    src = lens.unprojector()
    core = np.asarray(lens.params, dtype=float)[:4]
    if family == "equidistant":
        f = kb.fit(src, lens.imagersize, core)
        return Representation(family, _K(f.intrinsics), f.intrinsics[4:8], f, lens.lensmodel)
    target = {"rational_polynomial": "LENSMODEL_OPENCV8", "plumb_bob": "LENSMODEL_OPENCV5"}[family]
    f = fit_lensmodel(src, lens.imagersize, target, core)
    return Representation(family, _K(f.intrinsics), f.intrinsics[4:], f, lens.lensmodel)


def nearest_for_ros(lens: Lens) -> Representation:
    """The ROS distortion model matching the lens: exact where one exists (OPENCV4/5 -> plumb_bob,
    OPENCV8 -> rational_polynomial, Kannala-Brandt -> equidistant), else the better of the
    rational_polynomial and equidistant fits."""
    for family in ("plumb_bob", "rational_polynomial", "equidistant"):
        exact = _exact(lens, family)
        if exact is not None:
            return exact
    fits = [representation(lens, f) for f in ("rational_polynomial", "equidistant")]
    return min(fits, key=lambda r: r.fit.rms_px)


def nearest_kalibr(lens: Lens) -> Representation:
    """Kalibr's pinhole cameras know radtan (= plumb_bob without k3) and equidistant; for a fisheye
    the equidistant (pinhole-equi) model is the one to use: exact for Kannala-Brandt, fitted else."""
    return representation(lens, "equidistant")
