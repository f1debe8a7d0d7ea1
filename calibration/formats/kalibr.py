"""A Kalibr camchain entry (camchain.yaml) for one camera: camera_model pinhole with distortion
model equidistant (Kalibr's pinhole-equi, the Kannala-Brandt fisheye), intrinsics [fu, fv, pu, pv],
distortion_coeffs, resolution, rostopic. A single camera has no T_cn_cnm1 (that links a camera to
the previous one in the chain); the stereo extrinsics add it."""
from __future__ import annotations

import yaml

from .conversions import Representation


def kalibr_camchain(rep: Representation, imagersize: tuple[int, int], *, rostopic: str,
                    cam_id: str = "cam0") -> str:
    if rep.family != "equidistant":
        raise ValueError(f"Kalibr entry needs an equidistant representation, got {rep.family}")
    entry = {
        "camera_model": "pinhole",
        "intrinsics": [float(rep.K[0, 0]), float(rep.K[1, 1]), float(rep.K[0, 2]), float(rep.K[1, 2])],
        "distortion_model": "equidistant",
        "distortion_coeffs": [float(x) for x in rep.D],
        "resolution": [int(imagersize[0]), int(imagersize[1])],
        "rostopic": rostopic,
        "cam_overlaps": [],
    }
    body = yaml.safe_dump({cam_id: entry}, sort_keys=False, default_flow_style=None)
    return f"# {rep.note()}\n{body}"
