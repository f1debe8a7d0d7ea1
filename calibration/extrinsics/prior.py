"""The CAD extrinsics' expected error, from the CAD model's tolerance stack-up (cad/tolerances.py):
per thermal camera, how far it may sit from its CAD pose relative to the ZED X (the datum features,
the fits and the printer's and machinist's tolerances), as written beside the CAD extrinsics
(``pose_uncertainty.yaml``) and used by ``calibrate rig`` as the prior on its extrinsics.

The ZED right camera is in the same body as the ZED left (the anchor): the stack-up gives it nothing
to move by, and its pose relative to the left is the ZED's factory calibration, so it has no prior.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import yaml

from platform_tools.rig.frames import T_BODY_OPTICAL

#: the cameras the stack-up gives a prior to (camera short name -> the CAD model's camera name)
PRIOR_CAMERAS = {"thermal_left": "thermal_left", "thermal_right": "thermal_right"}


@dataclass(frozen=True)
class PosePrior:
    """A camera's pose error relative to the ZED left camera, as a 6x6 1-sigma covariance of the
    twist (x, y, z mm; rotation vector rad) in the camera's optical frame; ``body``: the stack-up's
    own summary in its body axes (PoseUncertainty.as_dict)."""
    camera: str
    covariance_optical: np.ndarray
    body: dict

    @property
    def sigma_optical(self) -> np.ndarray:
        return np.sqrt(np.diag(self.covariance_optical))


def _to_optical(cov_body: np.ndarray) -> np.ndarray:
    """A twist covariance in body axes (x forward, y left, z up) as the same twist in optical axes."""
    R = T_BODY_OPTICAL.R.T                      # body vectors -> optical vectors
    B = np.zeros((6, 6))
    B[:3, :3] = B[3:, 3:] = R
    return B @ cov_body @ B.T


def stack_up_priors(rig) -> dict[str, PosePrior]:
    """camera short name -> its :class:`PosePrior` from the rig's tolerance stack-up."""
    from cad.datums import camera_locations
    from cad.layout import layout
    from cad.tolerances import stack_up
    locations = camera_locations(layout(rig))
    out = {}
    for short, cam in PRIOR_CAMERAS.items():
        u = stack_up(locations, cam, relative_to="zed_x")
        out[short] = PosePrior(short, _to_optical(u.covariance), u.as_dict())
    return out


def pose_uncertainty_yaml(rig, priors: dict[str, PosePrior] | None = None) -> str:
    """``pose_uncertainty.yaml``: each camera's expected error from its CAD pose (worst case, RSS and
    1 sigma per axis) and the optical-frame covariance ``calibrate rig`` uses as its prior."""
    priors = stack_up_priors(rig) if priors is None else priors
    p = rig.desc.printing.printer
    hs = rig.desc.enclosure.heat_sink
    doc = {"what": "expected error of each camera's CAD pose relative to the ZED X (its datum features, fits and "
                   "tolerances; cad/tolerances.py): worst case, RSS and 1 sigma = RSS / 3 per axis",
           "inputs": {"printing.printer.tolerance_mm": p.tolerance_mm, "printing.printer.layer_mm": p.layer_mm,
                      "enclosure.heat_sink.tolerance_mm": hs.tolerance_mm,
                      "enclosure.heat_sink.bore_clearance_mm": hs.bore_clearance_mm},
           "rig_hash": rig.hash,
           "cameras": {c: dict(pr.body, covariance_optical={
               "axes": "optical frame (x right, y down, z forward): translation mm, rotation vector rad",
               "matrix": [[float(f"{v:.6g}") for v in row] for row in pr.covariance_optical]})
               for c, pr in priors.items()},
           "zed_right": "no prior: it is in the ZED X body with the anchor (the ZED's factory calibration)"}
    return "# the CAD extrinsics' expected error, from the tolerance stack-up\n" + \
        yaml.safe_dump(doc, sort_keys=False, default_flow_style=None, width=120)
