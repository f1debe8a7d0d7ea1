"""The CAD (or refined) extrinsics in the formats robots use: extrinsics.yaml, a Kalibr camchain, a
URDF of the rig's frames, mrcal .cameramodel files and a ROS 2 launch snippet of static transforms.

All of them are written from one :class:`~calibration.extrinsics.cad.FrameTree` (poses in the rig
frame, mm) and one set of camera models (``mrcal.cameramodel`` per camera short name: only their lenses are
used); lengths are metres in every file robots read
(URDF, launch, Kalibr, mrcal) and mm in extrinsics.yaml, where every key says its unit.
"""
from __future__ import annotations

import io
import math
import xml.etree.ElementTree as ET

import numpy as np
import yaml

from platform_tools.rig.cameras import camera_model, imagersize
from platform_tools.rig.frames import Pose

from .cad import CAMERAS, IMU, TOPIC_KEYS, FrameTree

CONVENTION = (
    "T_a_b is the pose of frame b in frame a: it maps a point from b into a, p_a = R p_b + t. "
    "The rig frame follows ROS REP-103 (x forward, y left, z up; origin at the ZED X camera centre). "
    "Camera optical frames are x right, y down, z forward (OpenCV, mrcal, ROS *_optical_frame). "
    "Translations in mm (xyz_mm) unless the key says metres; rpy_deg is URDF roll-pitch-yaw "
    "(fixed axes x, y, z: R = Rz(yaw) Ry(pitch) Rx(roll)); quaternion_xyzw is ROS order; "
    "rotvec_rad is Rodrigues (axis * angle) as mrcal's rt and OpenCV's rvec.")


def _clean(v: float, nd: int = 9) -> float:
    v = round(float(v), nd)
    return 0.0 if v == 0 else v


def pose_dict(T: Pose) -> dict:
    return {"xyz_mm": [_clean(x, 6) for x in T.t],
            "rpy_deg": [_clean(x, 9) for x in T.rpy_deg()],
            "quaternion_xyzw": [_clean(x, 12) for x in T.quaternion()],
            "rotvec_rad": [_clean(x, 12) for x in T.rt()[:3]],
            "matrix_mm": [[_clean(x, 9) for x in row] for row in T.matrix()]}


def extrinsics_yaml(tree: FrameTree, *, source: str, extra: dict | None = None) -> str:
    names = list(CAMERAS.values()) + [IMU]
    doc = {"convention": CONVENTION, "source": source, "rig_hash": tree.rig_hash,
           "frames": {n: dict(parent="rig", **pose_dict(tree.T_rig[n])) for n in names},
           "pairs": {f"T_{a}__{b}": dict(a=a, b=b, **pose_dict(tree.T(a, b)))
                     for a in names for b in names if a != b}}
    if extra:
        doc.update(extra)
    return f"# extrinsics of the rig ({source}); every pair T_a__b maps frame b into frame a\n" + \
        yaml.safe_dump(doc, sort_keys=False, default_flow_style=None, width=120)


def _m(T: Pose) -> list[list[float]]:
    M = T.matrix()
    M[:3, 3] /= 1000.0
    return [[_clean(x, 12) for x in row] for row in M]


def kalibr_camchain(tree: FrameTree, lenses: dict, topics: dict[str, str]) -> str:
    """Kalibr camchain: cam0..cam3 = zed_left, zed_right, thermal_left, thermal_right; T_cn_cnm1
    maps camera n-1 into camera n, T_cam_imu maps the IMU into the camera (metres). Intrinsics are
    Kalibr's pinhole with radtan (the ZED's rectified images) or equidistant (the Boson's fisheye,
    nominal: f theta with zero coefficients unless a solved lens is given)."""
    doc, note = {}, []
    prev = None
    for i, (short, frame) in enumerate(CAMERAS.items()):
        lens = lenses[short]
        lensmodel, intrinsics = lens.intrinsics()
        fx, fy, cx, cy = (float(x) for x in intrinsics[:4])
        if lensmodel == "LENSMODEL_PINHOLE":
            dist_model, coeffs = "radtan", [0.0, 0.0, 0.0, 0.0]
        elif lensmodel in ("LENSMODEL_STEREOGRAPHIC",):
            dist_model, coeffs = "equidistant", [0.0, 0.0, 0.0, 0.0]
            note.append(f"cam{i} ({short}): nominal fisheye written as equidistant f*theta, zero coefficients")
        else:
            from ..formats.conversions import nearest_kalibr
            rep = nearest_kalibr(lens)
            fx, fy, cx, cy = rep.K[0, 0], rep.K[1, 1], rep.K[0, 2], rep.K[1, 2]
            dist_model, coeffs = "equidistant", [float(x) for x in rep.D]
            note.append(f"cam{i} ({short}): {rep.note()}")
        entry = {"camera_model": "pinhole", "intrinsics": [float(fx), float(fy), float(cx), float(cy)], "distortion_model": dist_model,
                 "distortion_coeffs": coeffs, "resolution": list(imagersize(lens)),
                 "rostopic": topics.get(TOPIC_KEYS[short], f"/{short}/image_raw"),
                 "cam_overlaps": [j for j in range(len(CAMERAS)) if j != i],
                 "T_cam_imu": _m(tree.T(frame, IMU))}
        if prev is not None:
            entry["T_cn_cnm1"] = _m(tree.T(frame, prev))
        doc[f"cam{i}"] = entry
        prev = frame
    head = "# Kalibr camchain: T_cn_cnm1 maps camera n-1 into camera n, T_cam_imu maps the IMU into the camera (m)\n"
    head += "".join(f"# {n}\n" for n in note)
    return head + yaml.safe_dump(doc, sort_keys=False, default_flow_style=None, width=120)


def _fmt(x: float) -> str:
    return f"{_clean(x, 12):.12g}"


def urdf(tree: FrameTree, *, robot: str) -> str:
    """A URDF of the rig: a link per frame, a fixed joint per frame from its parent (metres, rpy)."""
    root = ET.Element("robot", name=robot)
    root.append(ET.Comment(" generated from the rig description through the CAD assembly; "
                           "optical frames are x right, y down, z forward "))
    ET.SubElement(root, "link", name="rig")
    for name in tree.T_rig:
        ET.SubElement(root, "link", name=name)
    for name, parent in tree.parent.items():
        T = tree.T(parent, name)
        j = ET.SubElement(root, "joint", name=f"{name}_joint", type="fixed")
        ET.SubElement(j, "parent", link=parent)
        ET.SubElement(j, "child", link=name)
        ET.SubElement(j, "origin", xyz=" ".join(_fmt(v / 1000.0) for v in T.t),
                      rpy=" ".join(_fmt(math.radians(a)) for a in T.rpy_deg()))
    ET.indent(root)
    return '<?xml version="1.0"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def launch_xml(tree: FrameTree) -> str:
    """ROS 2 launch (XML): one tf2_ros static_transform_publisher per joint of the URDF's tree."""
    root = ET.Element("launch")
    root.append(ET.Comment(" static transforms of the rig's frames (metres, quaternion x y z w); "
                           "include this file, or use the URDF with robot_state_publisher instead, not both "))
    for name, parent in tree.parent.items():
        T = tree.T(parent, name)
        q = T.quaternion()
        args = [f"--x {_fmt(T.t[0] / 1000)}", f"--y {_fmt(T.t[1] / 1000)}", f"--z {_fmt(T.t[2] / 1000)}",
                f"--qx {_fmt(q[0])}", f"--qy {_fmt(q[1])}", f"--qz {_fmt(q[2])}", f"--qw {_fmt(q[3])}",
                f"--frame-id {parent}", f"--child-frame-id {name}"]
        ET.SubElement(root, "node", pkg="tf2_ros", exec="static_transform_publisher",
                      name=f"tf_{name}", args=" ".join(args))
    ET.indent(root)
    return ET.tostring(root, encoding="unicode") + "\n"


def cameramodel_text(tree: FrameTree, short: str, lens, note: str,
                     optimization_inputs: dict | None = None) -> str:
    """An mrcal .cameramodel: the lens of ``lens`` (an mrcal.cameramodel; its pose is not used) and
    ``rt_fromref`` = the rig frame into the camera (metres)."""
    import mrcal
    rt = tree.camera(short).inverse().rt(metres=True)
    kw = {}
    if optimization_inputs is not None:
        kw = dict(optimization_inputs=optimization_inputs["inputs"], icam_intrinsics=optimization_inputs["icam"])
    model = camera_model(*lens.intrinsics(), imagersize(lens), rt) if not kw else mrcal.cameramodel(**kw)
    if kw:
        model.extrinsics_rt_fromref(rt)
    buf = io.StringIO()
    model.write(buf, note=note)
    return buf.getvalue()


def nominal_lenses(rig) -> dict:
    """camera short name (zed_left, ...) -> its nominal ``mrcal.cameramodel`` (platform_tools.rig.nominal)."""
    from platform_tools.rig.nominal import nominal_cameras
    by_frame = nominal_cameras(rig)
    return {short: by_frame[f] for short, f in CAMERAS.items()}


def all_files(tree: FrameTree, lenses: dict, rig, *, source: str,
              extra: dict | None = None, models: dict[str, str] | None = None) -> dict[str, str]:
    """Every output file, name -> text; ``pose_uncertainty.yaml`` is the CAD poses' expected error from the
    tolerance stack-up (calibration/extrinsics/prior.py), the prior ``calibrate rig`` refines them under."""
    from .prior import pose_uncertainty_yaml
    topics = dict(rig.to_data().get("on_device", {}).get("topics", {}))
    files = {"extrinsics.yaml": extrinsics_yaml(tree, source=source, extra=extra),
             "pose_uncertainty.yaml": pose_uncertainty_yaml(rig),
             "kalibr_camchain.yaml": kalibr_camchain(tree, lenses, topics),
             "rig.urdf": urdf(tree, robot=rig.desc.name),
             "static_transforms.launch.xml": launch_xml(tree)}
    for short in CAMERAS:
        name = f"{CAMERAS[short].removesuffix('_optical')}.cameramodel"
        files[name] = (models or {}).get(short) or cameramodel_text(
            tree, short, lenses[short], f"{short} ({source}); extrinsics rt_fromref: rig frame -> optical frame, "
                                        f"metres; rig hash {tree.rig_hash[:12]}")
    return files
