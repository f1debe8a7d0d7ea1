"""A scene with known geometry, seen by the rig's nominal cameras: the truth registration is checked against.

The scene is a few axis-aligned boxes in the rig frame (mm; x forward, y left, z up): a ground slab,
a back wall, a warm box that moves sideways over time and a near box in front of it (so that the
ZED and the thermal cameras, 46 mm apart vertically, see different occlusions). Everything above the
wall is sky: no hit, so the ZED depth is NaN there (and +inf beyond the depth range).

Each camera is the project's one camera value, the rig's nominal ``mrcal.cameramodel``
(``platform_tools.rig.nominal``: lens and pose from the rig description) scaled to the recorded image size
(``platform_tools.rig.cameras.scaled``). Rendering casts one ray per pixel centre (``mrcal.unproject``),
intersects the boxes and keeps the nearest hit; the ZED depth is the Z of the hit in the ZED left optical
frame, in metres, as zed-ros2-wrapper publishes it. The thermal counts follow the synthetic calibration
images' sensor response (``calibration.synth.sensor.counts``).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from calibration.synth import sensor
from calibration.synth.scene import AMBIENT_K
from platform_tools.rig.cameras import imagersize, scaled
from platform_tools.rig.nominal import nominal_camera

NO_HIT = -1


@dataclass(frozen=True)
class Box:
    name: str
    lo_mm: tuple[float, float, float]
    hi_mm: tuple[float, float, float]
    temperature_c: float
    bgr: tuple[int, int, int]


#: the scene; the box "walker" moves along y: y(t) = y0 + amplitude * sin(2 pi f t)
SCENE = {
    "boxes": [
        asdict(Box("ground", (-1000.0, -20000.0, -1600.0), (30000.0, 20000.0, -1500.0), 12.0, (90, 110, 100))),
        asdict(Box("wall", (7000.0, -9000.0, -1600.0), (7300.0, 9000.0, 1500.0), 18.0, (160, 150, 140))),
        asdict(Box("walker", (2600.0, -350.0, -1500.0), (3000.0, 350.0, 300.0), 34.0, (60, 90, 200))),
        asdict(Box("near", (1100.0, -700.0, -700.0), (1300.0, -300.0, -250.0), 26.0, (200, 160, 60))),
    ],
    "moving": {"box": "walker", "axis": 1, "amplitude_mm": 900.0, "frequency_hz": 0.15},
    "sky_temperature_c": -10.0,
    "checker_mm": 100.0,
    "max_depth_m": 20.0,
}


def boxes_at(scene: dict, t_s: float) -> list[Box]:
    m = scene["moving"]
    shift = m["amplitude_mm"] * np.sin(2 * np.pi * m["frequency_hz"] * t_s)
    out = []
    for b in scene["boxes"]:
        lo, hi = list(b["lo_mm"]), list(b["hi_mm"])
        if b["name"] == m["box"]:
            lo[m["axis"]] += shift
            hi[m["axis"]] += shift
        out.append(Box(b["name"], tuple(lo), tuple(hi), b["temperature_c"], tuple(b["bgr"])))
    return out


# ----------------------------------------------------------------------------- cameras
def sim_camera(rig, frame: str, width: int, height: int):
    """The nominal ``mrcal.cameramodel`` of optical frame ``frame`` for images of ``width`` x ``height`` px."""
    return scaled(nominal_camera(rig, frame), (width, height), what=frame)


def pose_in_rig(model) -> tuple[np.ndarray, np.ndarray]:
    """(R_rig_cam (3, 3): the optical axes as columns in the rig frame, c_rig_mm (3,): the camera centre in
    the rig frame, mm) of an ``mrcal.cameramodel`` posed in the rig frame (``rt_fromref`` in metres)."""
    import mrcal
    Rt_rig_cam = mrcal.invert_Rt(mrcal.Rt_from_rt(model.extrinsics_rt_fromref()))
    return Rt_rig_cam[:3], Rt_rig_cam[3] * 1000.0


def rays_rig(model) -> np.ndarray:
    """Unit ray direction of every pixel centre of ``model``, in the rig frame: (H, W, 3)."""
    import mrcal
    W, H = imagersize(model)
    u, v = np.meshgrid(np.arange(W, dtype=float), np.arange(H, dtype=float))
    d = mrcal.unproject(np.stack([u, v], -1), *model.intrinsics(), normalize=True)
    return d @ pose_in_rig(model)[0].T


def project_rig(model, p_rig_mm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pixel coordinates (..., 2) and optical-frame Z (..., mm) in ``model`` of rig-frame points (..., 3) mm."""
    import mrcal
    R_rig_cam, c_rig_mm = pose_in_rig(model)
    p_cam = (np.asarray(p_rig_mm, float) - c_rig_mm) @ R_rig_cam
    return mrcal.project(p_cam, *model.intrinsics()), p_cam[..., 2]


# ----------------------------------------------------------------------------- ray casting
def _hit_boxes(origin: np.ndarray, rays: np.ndarray, boxes: list[Box]) -> tuple[np.ndarray, np.ndarray]:
    """Distance (mm) along each unit ray to the nearest box, and the box's index (NO_HIT: none)."""
    flat = rays.reshape(-1, 3)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / flat
    best = np.full(len(flat), np.inf)
    which = np.full(len(flat), NO_HIT, np.int32)
    for i, b in enumerate(boxes):
        t1 = (np.asarray(b.lo_mm) - origin) * inv
        t2 = (np.asarray(b.hi_mm) - origin) * inv
        tn = np.nanmax(np.minimum(t1, t2), axis=1)
        tf = np.nanmin(np.maximum(t1, t2), axis=1)
        ok = (tf >= tn) & (tf > 0) & (tn > 0) & (tn < best)
        best[ok] = tn[ok]
        which[ok] = i
    return best.reshape(rays.shape[:-1]), which.reshape(rays.shape[:-1])


@dataclass
class Render:
    distance_mm: np.ndarray     # along the ray; inf: sky
    which: np.ndarray           # box index, NO_HIT: sky
    points_mm: np.ndarray       # hit points in the rig frame (nan: sky)
    z_m: np.ndarray             # optical-frame Z in metres (nan: sky)


def _render(c_rig_mm: np.ndarray, optical_z: np.ndarray, rays: np.ndarray, dist: np.ndarray,
            which: np.ndarray) -> Render:
    """The :class:`Render` of the nearest hits ``dist`` (mm along ``rays`` (H, W, 3) from the camera centre
    ``c_rig_mm``) on boxes ``which``; ``optical_z`` (3,) is the camera's optical axis in the rig frame."""
    hit = which != NO_HIT
    pts = np.where(hit[..., None], c_rig_mm + rays * np.where(hit, dist, 0.0)[..., None], np.nan)
    z = np.where(hit, dist * (rays @ optical_z) / 1000.0, np.nan)
    return Render(dist, which, pts, z)


def cast(cam, rays: np.ndarray, boxes: list[Box]) -> Render:
    """Cast ``rays`` (H, W, 3; :func:`rays_rig`) from the centre of ``cam`` (an ``mrcal.cameramodel`` posed
    in the rig frame) onto ``boxes``."""
    R_rig_cam, c_rig_mm = pose_in_rig(cam)
    dist, which = _hit_boxes(c_rig_mm, rays, boxes)
    return _render(c_rig_mm, R_rig_cam[:, 2], rays, dist, which)


def _checker(points_mm: np.ndarray, size_mm: float) -> np.ndarray:
    """A 3D checker: 0/1 alternating every size_mm along each rig axis (a checker on every box face)."""
    with np.errstate(invalid="ignore"):
        k = np.floor(np.nan_to_num(points_mm + 0.5) / size_mm).astype(np.int64).sum(-1)
    return (k & 1).astype(np.float32)


def colour(r: Render, boxes: list[Box], scene: dict) -> np.ndarray:
    """ZED view: each box's colour, modulated by the checker (bgr8); sky light blue."""
    lut = np.array([b.bgr for b in boxes] + [(235, 206, 170)], np.float32)
    base = lut[np.where(r.which == NO_HIT, len(boxes), r.which)]
    shade = 0.65 + 0.35 * _checker(r.points_mm, scene["checker_mm"])
    shade = np.where(r.which == NO_HIT, 1.0, shade)
    return np.clip(base * shade[..., None], 0, 255).astype(np.uint8)


def temperature_c(r: Render, boxes: list[Box], scene: dict) -> np.ndarray:
    """Thermal view: each box's temperature with a 1 K checker (emissivity pattern), sky cold."""
    lut = np.array([b.temperature_c for b in boxes] + [scene["sky_temperature_c"]], np.float32)
    t = lut[np.where(r.which == NO_HIT, len(boxes), r.which)]
    return t + np.where(r.which == NO_HIT, 0.0, _checker(r.points_mm, scene["checker_mm"]))


#: 0 degC in kelvin
ZERO_C_K = 273.15


def counts_from_c(t_c: np.ndarray) -> np.ndarray:
    """Raw Boson counts (float32, unrounded) of scene temperatures in degC (any shape), with the synthetic
    calibration images' sensor response (:func:`calibration.synth.sensor.counts`)."""
    return sensor.counts(np.asarray(t_c, np.float32) - np.float32(AMBIENT_K - ZERO_C_K))


def zed_depth_m(r: Render, scene: dict) -> np.ndarray:
    """ZED depth as published: Z in metres, NaN where nothing is seen, +inf beyond the depth range."""
    z = r.z_m.astype(np.float32)
    return np.where(z > scene["max_depth_m"], np.float32(np.inf), z)


class SceneRenderer:
    """Renders the scene for the rig's four cameras at recorded sizes; the static boxes are cast once
    per camera, the moving one every frame."""

    FRAMES = {"zed_left": "zed_x_left_optical", "zed_right": "zed_x_right_optical",
              "thermal_left": "thermal_left_optical", "thermal_right": "thermal_right_optical"}

    def __init__(self, rig, sizes: dict[str, tuple[int, int]], scene: dict = SCENE):
        self.scene = scene
        self.cams = {k: sim_camera(rig, f, *sizes["zed" if k.startswith("zed") else "thermal"])
                     for k, f in self.FRAMES.items()}
        self.poses = {k: pose_in_rig(c) for k, c in self.cams.items()}
        self.rays = {k: rays_rig(c) for k, c in self.cams.items()}
        boxes = boxes_at(scene, 0.0)
        self._moving = next(i for i, b in enumerate(boxes) if b.name == scene["moving"]["box"])
        static = [b for i, b in enumerate(boxes) if i != self._moving]
        self._static_index = np.array([i for i in range(len(boxes)) if i != self._moving] + [NO_HIT], np.int32)
        self._static = {k: _hit_boxes(self.poses[k][1], self.rays[k], static) for k in self.cams}

    def render(self, camera: str, t_s: float) -> tuple[Render, list[Box]]:
        boxes = boxes_at(self.scene, t_s)
        (R_rig_cam, c_rig_mm), rays = self.poses[camera], self.rays[camera]
        dist_s, which_s = self._static[camera]
        which_s = self._static_index[which_s]            # NO_HIT (-1) indexes the last entry: NO_HIT
        dist_m, hit_m = _hit_boxes(c_rig_mm, rays, [boxes[self._moving]])
        nearer = (hit_m != NO_HIT) & (dist_m < dist_s)
        dist = np.where(nearer, dist_m, dist_s)
        which = np.where(nearer, self._moving, which_s).astype(np.int32)
        return _render(c_rig_mm, R_rig_cam[:, 2], rays, dist, which), boxes
