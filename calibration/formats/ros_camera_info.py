"""ROS camera_info YAML, as camera_calibration_parsers reads and writes it (image_width,
image_height, camera_name, camera_matrix, distortion_model, distortion_coefficients,
rectification_matrix, projection_matrix; matrices as {rows, cols, data})."""
from __future__ import annotations

import numpy as np
import yaml

from .conversions import Representation


def _matrix(a: np.ndarray) -> dict:
    a = np.atleast_2d(np.asarray(a, dtype=float))
    return {"rows": int(a.shape[0]), "cols": int(a.shape[1]), "data": [float(x) for x in a.ravel()]}


class _FlowList(list):
    pass


def _flow_representer(dumper, data):
    return dumper.represent_sequence("tag:yaml.org,2002:seq", data, flow_style=True)


class _Dumper(yaml.SafeDumper):
    pass


_Dumper.add_representer(_FlowList, _flow_representer)


def ros_camera_info(rep: Representation, imagersize: tuple[int, int], *, camera_name: str) -> str:
    """The text of a camera_info YAML. The projection matrix is the camera matrix with a zero
    fourth column (a monocular camera, no rectification)."""
    P = np.zeros((3, 4))
    P[:, :3] = rep.K
    doc = {
        "image_width": int(imagersize[0]),
        "image_height": int(imagersize[1]),
        "camera_name": camera_name,
        "camera_matrix": _matrix(rep.K),
        "distortion_model": rep.family,
        "distortion_coefficients": _matrix(np.asarray(rep.D).reshape(1, -1)),
        "rectification_matrix": _matrix(np.eye(3)),
        "projection_matrix": _matrix(P),
    }
    for v in doc.values():
        if isinstance(v, dict):
            v["data"] = _FlowList(v["data"])
    body = yaml.dump(doc, Dumper=_Dumper, sort_keys=False)
    return f"# {rep.note()}\n{body}"
