"""Camera models for the export: the rig's nominal models (platform_tools.rig.nominal: lens as designed,
CAD-derived extrinsics) or a calibrated set of mrcal ``.cameramodel`` files, as ``calibrate nominal``
names them (``zed_x_left.cameramodel``, ``thermal_left.cameramodel``, ``thermal_right.cameramodel``;
all posed in one reference frame).

Recorded images are often smaller than the calibrated ones (the ZED publishes at
``on_device.zed_pub_downscale_factor``; the simulator scales everything): a model is scaled to the
recorded size per axis (pixel centres map as (q + 0.5) s - 0.5). A recording whose images do not
have the calibrated aspect ratio is refused: that calibration is not of these cameras.
"""
from __future__ import annotations

import hashlib
import io
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

#: frame name -> file name, as `calibrate nominal` writes them
FILES = {"zed_x_left_optical": "zed_x_left.cameramodel", "thermal_left_optical": "thermal_left.cameramodel",
         "thermal_right_optical": "thermal_right.cameramodel"}
#: recording stream -> frame
FRAME_OF = {"zed_left": "zed_x_left_optical", "thermal_left": "thermal_left_optical",
            "thermal_right": "thermal_right_optical"}
ASPECT_TOLERANCE = 0.01


class CalibrationError(Exception):
    """A calibration that cannot be used with this recording; one line."""


@dataclass(frozen=True)
class CameraCal:
    name: str
    lensmodel: str
    intrinsics: np.ndarray
    imagersize: tuple[int, int]
    rt_cam_ref: np.ndarray          # mrcal rt_fromref (metres)

    def scaled(self, width: int, height: int, what: str) -> "CameraCal":
        W, H = self.imagersize
        if (width, height) == (W, H):
            return self
        sx, sy = width / W, height / H
        # integer image sizes: allow one pixel of rounding on each axis besides the aspect tolerance
        if abs(sx - sy) > ASPECT_TOLERANCE * sx + 1.0 / W + 1.0 / H:
            raise CalibrationError(
                f"{what}: the calibration of {self.name} is for {W}x{H} images, the recording's are "
                f"{width}x{height} (aspect {width / height:.3f} vs {W / H:.3f}): not these cameras, or "
                f"cropped images; give the calibration of this recording with --calibration")
        k = np.array(self.intrinsics, float).copy()
        k[0] *= sx
        k[1] *= sy
        k[2] = (k[2] + 0.5) * sx - 0.5
        k[3] = (k[3] + 0.5) * sy - 0.5
        return replace(self, intrinsics=k, imagersize=(width, height))


@dataclass(frozen=True)
class Calibration:
    source: str                     # "nominal (rig <hash>)" or the folder
    sha256: str                     # of the model files' text
    cams: dict[str, CameraCal]

    def rt_a_b(self, a: str, b: str) -> np.ndarray:
        """mrcal rt mapping points in camera b's frame into camera a's (metres)."""
        import mrcal
        return mrcal.compose_rt(self.cams[a].rt_cam_ref, mrcal.invert_rt(self.cams[b].rt_cam_ref))

    def to_dict(self) -> dict:
        return {"source": self.source, "sha256": self.sha256,
                "cameras": {n: {"lensmodel": c.lensmodel, "intrinsics": [float(x) for x in c.intrinsics],
                                "imagersize": list(c.imagersize),
                                "rt_cam_ref": [float(x) for x in c.rt_cam_ref]} for n, c in self.cams.items()}}


def _from_model(name: str, m) -> CameraCal:
    lensmodel, intrinsics = m.intrinsics()
    return CameraCal(name, lensmodel, np.array(intrinsics, float), tuple(int(x) for x in m.imagersize()),
                     np.array(m.extrinsics_rt_fromref(), float))


def load_calibration(rig, path: Path | None = None) -> Calibration:
    import mrcal
    texts, cams = [], {}
    if path is None:
        from platform_tools.rig.nominal import nominal_cameras
        for name, m in nominal_cameras(rig).items():
            if name in FILES:
                buf = io.StringIO()
                m.write(buf)
                texts.append(buf.getvalue())
                cams[name] = _from_model(name, m)
        source = f"nominal (rig {rig.desc.name} {rig.hash[:12]})"
    else:
        path = Path(path)
        if not path.is_dir():
            raise CalibrationError(f"{path}: not a folder of .cameramodel files")
        for frame, fname in FILES.items():
            f = path / fname
            if not f.is_file():
                raise CalibrationError(f"{f}: missing (the calibration folder needs {', '.join(FILES.values())})")
            try:
                text = f.read_text()
                cams[frame] = _from_model(frame, mrcal.cameramodel(str(f)))
            except Exception as exc:  # noqa: BLE001  mrcal raises plain Exceptions on bad files
                raise CalibrationError(f"{f}: not a readable mrcal camera model ({exc})") from None
            texts.append(text)
        source = str(path)
    if cams["zed_x_left_optical"].lensmodel != "LENSMODEL_PINHOLE":
        # the ZED publishes rectified images: a distortion model here means a wrong file
        raise CalibrationError(f"{source}: the ZED left model is {cams['zed_x_left_optical'].lensmodel}; the "
                               f"recorded ZED images are rectified (LENSMODEL_PINHOLE expected)")
    sha = hashlib.sha256("".join(texts).encode()).hexdigest()
    return Calibration(source, sha, cams)
