"""Nominal camera models from the rig description: the lens as designed, posed where the rig puts it.

A nominal model is where a calibration starts (its focal-length seed) and what a synthetic camera
is made from before any distortion is added. Projections:

- ``pinhole`` cameras (the ZED X): ``LENSMODEL_PINHOLE``, f = focal length / pixel pitch.
- ``fisheye`` cameras (the Boson with its 95 deg lens): ``LENSMODEL_STEREOGRAPHIC`` with the same f
  (r = 2 f tan(theta/2)), which agrees with a pinhole at the centre and stays finite to 180 deg.

Extrinsics are written as mrcal expects: ``rt_fromref`` maps the reference frame into the camera's
optical frame; the reference is the rig frame, in metres.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from platform_tools.rig import Rig

LENSMODEL_FOR_PROJECTION = {"pinhole": "LENSMODEL_PINHOLE", "fisheye": "LENSMODEL_STEREOGRAPHIC"}


@dataclass(frozen=True)
class NominalCamera:
    name: str                 # the sensor frame, e.g. thermal_left_optical
    lensmodel: str
    intrinsics: np.ndarray    # fx fy cx cy
    imagersize: tuple[int, int]
    rt_cam_rig_m: np.ndarray  # mrcal rt_fromref (rig frame -> camera optical frame), metres


def nominal_cameras(rig: Rig) -> list[NominalCamera]:
    cams = []
    for frame in rig.sensor_frames().values():
        if not frame.optical or frame.camera_model is None:
            continue
        spec = rig.camera_model(frame.camera_model)
        f = rig.focal_px(spec)
        w, h = spec.width_px, spec.height_px
        intrinsics = np.array([f, f, (w - 1) / 2.0, (h - 1) / 2.0])
        rt = frame.T_rig.inverse().rt(metres=True)
        cams.append(NominalCamera(frame.name, LENSMODEL_FOR_PROJECTION[spec.projection], intrinsics, (w, h), rt))
    return cams


def to_cameramodel(cam: NominalCamera):
    import mrcal
    return mrcal.cameramodel(intrinsics=(cam.lensmodel, cam.intrinsics), imagersize=cam.imagersize,
                             extrinsics_rt_fromref=cam.rt_cam_rig_m)
