"""The calibration an export uses: the rig's nominal models (platform_tools.rig.nominal: lens as designed,
CAD-derived extrinsics) or a calibrated set of mrcal ``.cameramodel`` files, as ``calibrate nominal``
names them (``zed_x_left.cameramodel``, ``thermal_left.cameramodel``, ``thermal_right.cameramodel``;
all posed in one reference frame).

Each camera is the project's one camera value, an ``mrcal.cameramodel`` (platform_tools.rig.cameras).
Recorded images are often smaller than the calibrated ones (the ZED publishes at
``on_device.zed_pub_downscale_factor``; the simulator scales everything): :func:`at_recorded_size` carries a
model to the recorded size with :func:`platform_tools.rig.cameras.scaled`. A recording whose images do not
have the calibrated aspect ratio is refused: that calibration is not of these cameras.

A bag may carry its own calibration as ``sensor_msgs/CameraInfo`` topics (the released TartanRGBT stack records
the ZED's factory calibration and the Bosons' models): :func:`for_recording` then takes each camera's
intrinsics from its camera_info (plumb_bob -> LENSMODEL_OPENCV5, or PINHOLE when every coefficient is 0;
rational_polynomial -> OPENCV8) and its pose from the rig's nominal extrinsics (camera_info holds none). The
rig's nominal models are the fallback for a camera without camera_info (or with an uncalibrated one, K = 0);
``--calibration DIR`` overrides both. ``Calibration.source`` says which was used, per camera.
"""
from __future__ import annotations

import hashlib
import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from platform_tools.rig.cameras import ImageSizeError, camera_model, check_aspect, imagersize, scaled

#: frame name -> file name, as `calibrate nominal` writes them
FILES = {"zed_x_left_optical": "zed_x_left.cameramodel", "thermal_left_optical": "thermal_left.cameramodel",
         "thermal_right_optical": "thermal_right.cameramodel"}
#: recording stream -> frame
FRAME_OF = {"zed_left": "zed_x_left_optical", "thermal_left": "thermal_left_optical",
            "thermal_right": "thermal_right_optical"}


class CalibrationError(Exception):
    """A calibration that cannot be used with this recording; one line."""


def model_to_dict(model) -> dict:
    """An ``mrcal.cameramodel`` as plain JSON values: lensmodel, intrinsics (N,), imagersize [W, H] (px) and
    rt_cam_ref (6,: Rodrigues r, then t in metres; maps the reference frame into the camera)."""
    lensmodel, intrinsics = model.intrinsics()
    return {"lensmodel": lensmodel, "intrinsics": [float(x) for x in intrinsics],
            "imagersize": list(imagersize(model)),
            "rt_cam_ref": [float(x) for x in model.extrinsics_rt_fromref()]}


def model_from_dict(d: dict):
    """The ``mrcal.cameramodel`` of :func:`model_to_dict`'s dict."""
    return camera_model(d["lensmodel"], d["intrinsics"], tuple(d["imagersize"]), d["rt_cam_ref"])


def at_recorded_size(name: str, model, size: tuple[int, int], what: str):
    """``model`` (the calibration of camera ``name``) for recorded images of ``size`` (W, H) px; raises
    :class:`CalibrationError` naming ``what`` (the recording) when the aspect ratio is not the calibrated one."""
    W, H = imagersize(model)
    width, height = int(size[0]), int(size[1])
    try:
        check_aspect((W, H), (width, height), what=what)
    except ImageSizeError:
        raise CalibrationError(
            f"{what}: the calibration of {name} is for {W}x{H} images, the recording's are "
            f"{width}x{height} (aspect {width / height:.3f} vs {W / H:.3f}): not these cameras, or "
            f"cropped images; give the calibration of this recording with --calibration") from None
    return scaled(model, (width, height), what=what)


def rt_a_b(models: dict, a: str, b: str) -> np.ndarray:
    """mrcal rt (6,) mapping points in camera b's frame into camera a's (metres); ``models``: frame name ->
    ``mrcal.cameramodel``, all posed in one reference frame."""
    import mrcal
    return mrcal.compose_rt(models[a].extrinsics_rt_fromref(), mrcal.invert_rt(models[b].extrinsics_rt_fromref()))


@dataclass(frozen=True)
class Calibration:
    source: str                     # "nominal (rig <hash>)" or the folder
    sha256: str                     # of the model files' text
    cams: dict                      # frame name -> mrcal.cameramodel

    def rt_a_b(self, a: str, b: str) -> np.ndarray:
        """mrcal rt mapping points in camera b's frame into camera a's (metres)."""
        return rt_a_b(self.cams, a, b)

    def to_dict(self) -> dict:
        return {"source": self.source, "sha256": self.sha256,
                "cameras": {n: model_to_dict(m) for n, m in self.cams.items()}}


#: camera_info distortion model -> (mrcal lens model, number of coefficients it takes)
DISTORTION = {"plumb_bob": ("LENSMODEL_OPENCV5", 5), "rational_polynomial": ("LENSMODEL_OPENCV8", 8)}


def from_camera_info(info: dict, where: str) -> tuple[str, list[float]] | None:
    """(mrcal lens model, intrinsics) of a camera_info dict (recording.Recording.camera_info), None when it is
    uncalibrated (K all 0); :class:`CalibrationError` naming ``where`` for a model this cannot represent."""
    k = info["k"]
    fx, fy, cx, cy = k[0], k[4], k[2], k[5]
    if fx <= 0 or fy <= 0 or info["width"] <= 0 or info["height"] <= 0:
        return None
    d = list(info["d"])
    if not any(d):
        return "LENSMODEL_PINHOLE", [fx, fy, cx, cy]
    dm = info["distortion_model"] or "plumb_bob"
    if dm not in DISTORTION or len(d) > DISTORTION[dm][1]:
        raise CalibrationError(f"{where}: distortion model {dm!r} with {len(d)} coefficients: not readable "
                               f"(expected {' or '.join(DISTORTION)}); give the calibration with --calibration")
    lens, n = DISTORTION[dm]
    return lens, [fx, fy, cx, cy] + d + [0.0] * (n - len(d))


def for_recording(rig, rec, path: Path | None = None) -> Calibration:
    """The calibration an export of ``rec`` uses: ``path``'s models when given, else each camera's camera_info
    (posed with the nominal extrinsics), else the rig's nominal model."""
    if path is not None:
        return load_calibration(rig, path)
    nominal = load_calibration(rig)
    cams, used = dict(nominal.cams), []
    for stream, frame in FRAME_OF.items():
        info = rec.camera_info.get(stream)
        lens = from_camera_info(info, f"{rec.path}: {info['topic']}") if info else None
        if lens is None:
            continue
        cams[frame] = camera_model(lens[0], lens[1], (info["width"], info["height"]),
                                   nominal.cams[frame].extrinsics_rt_fromref())
        used.append(stream)
    if not used:
        return nominal
    rest = [s for s, f in FRAME_OF.items() if s not in used]
    source = (f"camera_info ({', '.join(used)}; extrinsics nominal)"
              + (f", {nominal.source} for {', '.join(rest)}" if rest else f", rig {rig.desc.name} {rig.hash[:12]}"))
    texts = []
    for frame in FILES:
        buf = io.StringIO()
        cams[frame].write(buf)
        texts.append(buf.getvalue())
    return Calibration(source, hashlib.sha256("".join(texts).encode()).hexdigest(), cams)


#: the ZED right model in a calibration folder (needed only for depth from the stereo pair)
ZED_RIGHT_FILE = "zed_x_right.cameramodel"


def zed_right(rig, rec, path: Path | None = None):
    """The ZED right camera's model for stereo depth: ``path``/zed_x_right.cameramodel when ``--calibration`` is
    given, else the recording's right camera_info (posed with the nominal extrinsics), else the rig's nominal model
    when the recording's layout has no camera_info topic for it (rectified images, this rig's layout). A layout
    that publishes raw images with their camera_info (TartanRGBT) without a right camera_info, or a folder without
    the file: :class:`CalibrationError`, one line naming the topic or file."""
    from platform_tools.rig.nominal import nominal_camera
    import mrcal
    frame = "zed_x_right_optical"
    if path is not None:
        f = Path(path) / ZED_RIGHT_FILE
        if not f.is_file():
            raise CalibrationError(f"{f}: missing: depth from the stereo pair needs the ZED right model beside "
                                   f"the others (or --depth recorded)")
        try:
            return mrcal.cameramodel(str(f))
        except Exception as exc:  # noqa: BLE001  mrcal raises plain Exceptions on bad files
            raise CalibrationError(f"{f}: not a readable mrcal camera model ({exc})") from None
    nominal = nominal_camera(rig, frame)
    info = rec.camera_info.get("zed_right")
    lens = from_camera_info(info, f"{rec.path}: {info['topic']}") if info else None
    if lens is not None:
        return camera_model(lens[0], lens[1], (info["width"], info["height"]), nominal.extrinsics_rt_fromref())
    topic = rec._topics.get("zed_right_info")
    if topic is not None or rec.camera_info.get("zed_left"):
        what = (f"{topic}: no camera_info messages" if topic and not info else
                f"{topic}: uncalibrated camera_info (K = 0)" if topic else "no zed_right_info topic in the "
                f"{rec.layout} layout (the left image has a camera_info: raw images)")
        raise CalibrationError(f"{rec.path}: {what}: depth from the stereo pair needs the ZED right calibration "
                               f"(its camera_info, or --calibration DIR with {ZED_RIGHT_FILE})")
    return nominal


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
                cams[name] = m
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
                cams[frame] = mrcal.cameramodel(str(f))
            except Exception as exc:  # noqa: BLE001  mrcal raises plain Exceptions on bad files
                raise CalibrationError(f"{f}: not a readable mrcal camera model ({exc})") from None
            texts.append(text)
        source = str(path)
    zed_lensmodel = cams["zed_x_left_optical"].intrinsics()[0]
    if zed_lensmodel != "LENSMODEL_PINHOLE":
        # the ZED publishes rectified images: a distortion model here means a wrong file
        raise CalibrationError(f"{source}: the ZED left model is {zed_lensmodel}; the "
                               f"recorded ZED images are rectified (LENSMODEL_PINHOLE expected)")
    sha = hashlib.sha256("".join(texts).encode()).hexdigest()
    return Calibration(source, sha, cams)
