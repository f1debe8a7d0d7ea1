"""Truth files of a :class:`~calibration.synth.truth_lens.RadialLens` that independent tools read:

- ``kannala-brandt``: ``truth_fisheye.yaml``, an OpenCV FileStorage YAML (camera_matrix K,
  distortion_coefficients D = k1..k4, image_width, image_height) for cv2.fisheye;
- ``stereographic``: ``truth.cameramodel`` (LENSMODEL_STEREOGRAPHIC: fx fy cx cy);
- ``plumb-bob``: ``truth.cameramodel`` (LENSMODEL_OPENCV5: fx fy cx cy k1 k2 p1=0 p2=0 k3) and
  ``truth_camera_info.yaml`` (ROS camera_info, distortion_model plumb_bob, as it was published);
- every family: ``truth_table.npz``, the dense projection table (``q`` (Ny, Nx, 2) pixels on a 4 px
  grid over the whole imager, edges included; ``v`` (Ny, Nx, 3) their unit rays, NaN past the lens'
  field; ``family``, ``intrinsics``, ``imagersize``).

Each writer returns the names of the files it wrote.
"""
from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from .truth_lens import RadialLens

TABLE_STEP_PX = 4.0


def camera_matrix(lens: RadialLens) -> np.ndarray:
    """K (3, 3)."""
    return np.array([[lens.fx, 0.0, lens.cx], [0.0, lens.fy, lens.cy], [0.0, 0.0, 1.0]])


def write_fisheye_yaml(path: Path, lens: RadialLens) -> None:
    import cv2
    W, H = lens.size
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    try:
        fs.write("model", "fisheye (Kannala-Brandt): theta_d = theta (1 + k1 th^2 + k2 th^4 + k3 th^6 + k4 th^8)")
        fs.write("image_width", int(W))
        fs.write("image_height", int(H))
        fs.write("camera_matrix", camera_matrix(lens))
        fs.write("distortion_coefficients", np.array(lens.coeffs, float).reshape(4, 1))
    finally:
        fs.release()


def mrcal_equivalent(lens: RadialLens) -> tuple[str, list[float]] | None:
    """(mrcal lensmodel, intrinsics) representing ``lens`` exactly, or None (Kannala-Brandt)."""
    if lens.family == "stereographic":
        return "LENSMODEL_STEREOGRAPHIC", [lens.fx, lens.fy, lens.cx, lens.cy]
    if lens.family == "plumb-bob":
        k1, k2, k3 = lens.coeffs
        return "LENSMODEL_OPENCV5", [lens.fx, lens.fy, lens.cx, lens.cy, k1, k2, 0.0, 0.0, k3]
    return None


def write_cameramodel(path: Path, lens: RadialLens, note: str) -> None:
    from platform_tools.rig.cameras import camera_model
    lm, intr = mrcal_equivalent(lens)
    buf = io.StringIO()
    camera_model(lm, intr, lens.size).write(buf, note=note)
    path.write_text(buf.getvalue())


def write_camera_info(path: Path, lens: RadialLens) -> None:
    """ROS camera_info YAML, plumb_bob (k1 k2 p1 p2 k3)."""
    W, H = lens.size
    k1, k2, k3 = lens.coeffs
    K = camera_matrix(lens).ravel().tolist()
    P = [lens.fx, 0.0, lens.cx, 0.0, 0.0, lens.fy, lens.cy, 0.0, 0.0, 0.0, 1.0, 0.0]

    def mat(rows, cols, data):
        return f"\n  rows: {rows}\n  cols: {cols}\n  data: [{', '.join(repr(float(x)) for x in data)}]"
    path.write_text(
        f"image_width: {W}\nimage_height: {H}\ncamera_name: truth\n"
        f"camera_matrix:{mat(3, 3, K)}\ndistortion_model: plumb_bob\n"
        f"distortion_coefficients:{mat(1, 5, [k1, k2, 0.0, 0.0, k3])}\n"
        f"rectification_matrix:{mat(3, 3, [1, 0, 0, 0, 1, 0, 0, 0, 1])}\n"
        f"projection_matrix:{mat(3, 4, P)}\n")


def write_table(path: Path, lens: RadialLens) -> None:
    q, v = lens.projection_table(TABLE_STEP_PX)
    lm, intr = lens.intrinsics()
    with open(path, "wb") as f:
        np.savez_compressed(f, q=q, v=v, family=lm, intrinsics=intr, imagersize=np.array(lens.size))


def write_truth_files(folder: Path, lens: RadialLens, note: str) -> list[str]:
    """Every truth file of ``lens`` into ``folder``; see the module docstring."""
    folder = Path(folder)
    names = []
    if lens.family == "kannala-brandt":
        write_fisheye_yaml(folder / "truth_fisheye.yaml", lens)
        names.append("truth_fisheye.yaml")
    if mrcal_equivalent(lens) is not None:
        write_cameramodel(folder / "truth.cameramodel", lens, note)
        names.append("truth.cameramodel")
    if lens.family == "plumb-bob":
        write_camera_info(folder / "truth_camera_info.yaml", lens)
        names.append("truth_camera_info.yaml")
    write_table(folder / "truth_table.npz", lens)
    names.append("truth_table.npz")
    return names
