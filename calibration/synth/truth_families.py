"""The truth lenses synthetic sets can be rendered through, by family name, for a given sensor size.

- ``opencv8``: the project's nominal lens (calibration/synth/lens.py), the solver's own default
  family: kept as the anchor, not as test data independent of the solver.
- ``kannala-brandt``: a polynomial fisheye (theta_d = theta (1 + k1 theta^2 + ... + k4 theta^8)),
  f from the rig description (4.9 mm / 12 um), k2..k4 fixed below and k1 set so that the image
  half-width sits at half the rig's HFoV; fy 0.2 % longer than fx, the principal point off centre the
  other way from the OPENCV8 lens' (nothing shared with it but f and the HFoV).
- ``stereographic``: rho = 2 tan(theta / 2), f set so the half-width sits at half the HFoV (364 px on
  640 px at 95 deg: the "f = W / (4 tan(HFoV/4))" of mrcal's docs), a small fy/fx and centre offset.
- ``boson-published``: the published camera_info of a Boson 640 + 4.9 mm (AirLab's flir_ros_sync,
  left camera; /work/shared/reference/upstream-tartanrgbt.md): plumb_bob fx 411.34, fy 412.67,
  cx 320.40, cy 251.97, k1 -0.3565, k2 0.1078. A real lens' calibration, in the model it was
  published in (two radial terms, monotonic over the whole image: 93.5 deg HFoV, 54 deg at the corners).

Other sensor sizes (320x256, 382x288, 640x512): the same field of view, so every focal length
scales with W / 640 and the principal point keeps its offset from the centre scaled the same way
(an assumption: a Boson 320 has the 640's 12 um pixels and would see half the field through the
same lens; this keeps the boards' angular layout comparable across sizes).
"""
from __future__ import annotations

import math

from .truth_lens import RadialLens

SENSOR_SIZES = ((320, 256), (382, 288), (640, 512))
FAMILIES = ("opencv8", "kannala-brandt", "stereographic", "boson-published")

KB_HIGHER_TERMS = (0.004, -0.002, 0.0003)     # k2, k3, k4 of the Kannala-Brandt truth
KB_FY_OVER_FX = 1.002
KB_PRINCIPAL_OFFSET_PX = (-3.1, 2.4)
STEREO_FY_OVER_FX = 0.9985
STEREO_PRINCIPAL_OFFSET_PX = (1.4, 3.0)
# AirLab flir_ros_sync camera_info, Boson 640 + 4.9 mm, left camera (640x512, plumb_bob)
PUBLISHED_BOSON = dict(fx=411.34, fy=412.67, cx=320.40, cy=251.97, k1=-0.3565, k2=0.1078, k3=0.0)
PUBLISHED_SIZE = (640, 512)      # the image size that published calibration is for


def _rig_optics(rig) -> tuple[float, float, tuple[int, int]]:
    """(focal length px, HFoV deg, imager size (W, H)) of the thermal camera in the rig description."""
    if rig is None:
        from platform_tools.rig import load_rig
        rig = load_rig()
    spec = rig.camera_model(rig.desc.sensors.thermal.camera_model)
    return rig.focal_px(spec), float(spec.hfov_deg.value), (int(spec.width_px), int(spec.height_px))


def _centre(size: tuple[int, int], offset_px: tuple[float, float], scale: float) -> tuple[float, float]:
    return (size[0] - 1) / 2 + offset_px[0] * scale, (size[1] - 1) / 2 + offset_px[1] * scale


def kannala_brandt(size=None, rig=None) -> RadialLens:
    f, hfov, native = _rig_optics(rig)
    size = size or native
    scale = size[0] / native[0]
    half = math.radians(hfov) / 2
    k2, k3, k4 = KB_HIGHER_TERMS
    t2 = half * half
    # theta (1 + k1 t2 + k2 t2^2 + k3 t2^3 + k4 t2^4) = (W/2) / f at theta = half HFoV
    k1 = ((native[0] / 2) / (f * half) - 1 - k2 * t2 ** 2 - k3 * t2 ** 3 - k4 * t2 ** 4) / t2
    cx, cy = _centre(size, KB_PRINCIPAL_OFFSET_PX, scale)
    return RadialLens("kannala-brandt", f * scale, f * scale * KB_FY_OVER_FX, cx, cy, (k1, k2, k3, k4),
                      tuple(size), name=f"Kannala-Brandt fisheye, {hfov:g} deg HFoV")


def stereographic(size=None, rig=None) -> RadialLens:
    _, hfov, native = _rig_optics(rig)
    size = size or native
    scale = size[0] / native[0]
    f = (native[0] / 2) / (2 * math.tan(math.radians(hfov) / 4))
    cx, cy = _centre(size, STEREO_PRINCIPAL_OFFSET_PX, scale)
    return RadialLens("stereographic", f * scale, f * scale * STEREO_FY_OVER_FX, cx, cy, (), tuple(size),
                      name=f"stereographic, {hfov:g} deg HFoV")


def boson_published(size=None, rig=None) -> RadialLens:
    p = PUBLISHED_BOSON
    size = size or PUBLISHED_SIZE
    scale = size[0] / PUBLISHED_SIZE[0]
    off = (p["cx"] - (PUBLISHED_SIZE[0] - 1) / 2, p["cy"] - (PUBLISHED_SIZE[1] - 1) / 2)
    cx, cy = _centre(size, off, scale)
    return RadialLens("plumb-bob", p["fx"] * scale, p["fy"] * scale, cx, cy, (p["k1"], p["k2"], p["k3"]),
                      tuple(size), name="published Boson 640 + 4.9 mm (AirLab flir_ros_sync, plumb_bob)")


def truth_lens(family: str, size=None, rig=None):
    """The truth lens ``family`` (one of :data:`FAMILIES`) for a ``size`` (W, H) sensor: a
    :class:`RadialLens`, or for ``opencv8`` the nominal ``mrcal.cameramodel``."""
    size = (int(size[0]), int(size[1])) if size is not None else None
    if family == "opencv8":
        from platform_tools.rig.cameras import camera_model

        from .lens import fit_opencv8
        f, hfov, native = _rig_optics(rig)
        size = size or native
        scale = size[0] / native[0]
        return camera_model("LENSMODEL_OPENCV8", fit_opencv8(f * scale, size[0], size[1], hfov), size)
    makers = {"kannala-brandt": kannala_brandt, "stereographic": stereographic, "boson-published": boson_published}
    if family not in makers:
        raise ValueError(f"unknown truth lens {family!r}; known: {', '.join(FAMILIES)}")
    return makers[family](size, rig)
