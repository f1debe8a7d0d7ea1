"""Nominal camera models from the rig description: the lens as designed, posed where the rig puts it.

A nominal model is where a calibration starts (its focal-length seed) and what a synthetic camera
is made from before any distortion is added. Projections:

- ``pinhole`` cameras (the ZED X): ``LENSMODEL_PINHOLE``, f = focal length / pixel pitch.
- ``fisheye`` cameras (the Boson with its 95 deg lens): ``LENSMODEL_STEREOGRAPHIC`` with the same f
  (r = 2 f tan(theta/2)), which agrees with a pinhole at the centre and stays finite to 180 deg.

Each is the project's one camera value, an ``mrcal.cameramodel`` (:mod:`platform_tools.rig.cameras`), whose
``rt_fromref`` maps the reference frame into the camera's optical frame; the reference is the rig frame, in
metres.
"""
from __future__ import annotations

import numpy as np

from platform_tools.rig.cameras import camera_model
from platform_tools.rig.model import Rig

LENSMODEL_FOR_PROJECTION = {"pinhole": "LENSMODEL_PINHOLE", "fisheye": "LENSMODEL_STEREOGRAPHIC"}


def nominal_cameras(rig: Rig) -> dict:
    """Optical frame name (e.g. ``thermal_left_optical``) -> its nominal ``mrcal.cameramodel``, in the order of
    the rig's sensor frames."""
    cams = {}
    for frame in rig.sensor_frames().values():
        if not frame.optical or frame.camera_model is None:
            continue
        spec = rig.camera_model(frame.camera_model)
        f = rig.focal_px(spec)
        w, h = spec.width_px, spec.height_px
        intrinsics = np.array([f, f, (w - 1) / 2.0, (h - 1) / 2.0])
        cams[frame.name] = camera_model(LENSMODEL_FOR_PROJECTION[spec.projection], intrinsics, (w, h),
                                        frame.T_rig.inverse().rt(metres=True))
    return cams


def nominal_camera(rig: Rig, frame: str):
    """The nominal ``mrcal.cameramodel`` of one optical frame; KeyError naming the frames there are."""
    cams = nominal_cameras(rig)
    if frame not in cams:
        raise KeyError(f"{frame}: no such camera; the rig has {', '.join(cams)}")
    return cams[frame]
