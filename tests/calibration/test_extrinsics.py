"""`calibrate extrinsics --from-cad`: the CAD poses, every output format, and the STEP's placements."""
from __future__ import annotations

import math
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
import yaml

from calibration.extrinsics.cad import CAMERAS, IMU, cad_frames
from platform_tools.rig.frames import Pose, rpy_to_matrix
from platform_tools.rig import load_rig

#: the extrinsics are read from the built CAD assembly: the quick loop (make test-fast) leaves them to make test
pytestmark = pytest.mark.slow

REPO = Path(__file__).resolve().parents[2]
MOVED = ("sensors.thermal.pose.xyz_mm=[-2,0,-50]", "sensors.thermal.pose.rpy_deg=[0.5,-1,0.5]")


def run(*args):
    return subprocess.run([sys.executable, "-m", "calibration.cli", *args], cwd=REPO, capture_output=True, text=True)


@pytest.fixture(scope="module")
def moved_rig():
    return load_rig(None, MOVED)


@pytest.fixture(scope="module")
def out(tmp_path_factory):
    d = tmp_path_factory.mktemp("ext") / "out"
    r = run("extrinsics", "--from-cad", "--out", str(d), *sum((["--set", s] for s in MOVED), []), "-q")
    assert r.returncode == 0, r.stderr
    return d


def test_cad_frames_equal_rig_frames(moved_rig):
    tree = cad_frames(moved_rig)
    for name, T in tree.T_rig.items():
        assert T.isclose(moved_rig.frame(name), mm=1e-9, deg=1e-9), name
    # moving the thermal pair in the rig description moved it in the extrinsics
    base = cad_frames(load_rig())
    assert not tree.camera("thermal_left").isclose(base.camera("thermal_left"), mm=1.0, deg=1.0)


@pytest.mark.slow
def test_outputs(out, moved_rig):
    tree = cad_frames(moved_rig)
    names = sorted(p.name for p in out.iterdir())
    assert names == sorted(["extrinsics.yaml", "kalibr_camchain.yaml", "rig.urdf", "static_transforms.launch.xml",
                            "pose_uncertainty.yaml", "zed_x_left.cameramodel", "zed_x_right.cameramodel",
                            "thermal_left.cameramodel", "thermal_right.cameramodel"])
    doc = yaml.safe_load((out / "extrinsics.yaml").read_text())
    assert "maps" in doc["convention"] and "x right, y down, z forward" in doc["convention"]
    frames = list(CAMERAS.values()) + [IMU]
    assert len(doc["pairs"]) == len(frames) * (len(frames) - 1)
    for key, p in doc["pairs"].items():
        M = np.array(p["matrix_mm"])
        assert Pose.from_matrix(M).isclose(tree.T(p["a"], p["b"]), mm=1e-6, deg=1e-6), key
        assert Pose.from_xyz_rpy_deg(p["xyz_mm"], p["rpy_deg"]).isclose(tree.T(p["a"], p["b"]), mm=1e-5, deg=1e-6)


def _compose_urdf(text: str) -> dict[str, Pose]:
    root = ET.fromstring(text)
    joints = {}
    for j in root.findall("joint"):
        o = j.find("origin")
        xyz = [float(v) * 1000 for v in o.get("xyz").split()]
        rpy = [float(v) for v in o.get("rpy").split()]
        joints[j.find("child").get("link")] = (j.find("parent").get("link"), Pose(rpy_to_matrix(*rpy), xyz))
    links = {l.get("name") for l in root.findall("link")}
    assert set(joints) | {"rig"} == links
    out = {}

    def pose(name):
        if name == "rig":
            return Pose.identity()
        if name not in out:
            parent, T = joints[name]
            out[name] = pose(parent) @ T
        return out[name]
    for name in joints:
        pose(name)
    return out


def test_urdf_and_launch_compose_to_the_frames(out, moved_rig):
    tree = cad_frames(moved_rig)
    got = _compose_urdf((out / "rig.urdf").read_text())
    assert set(got) == set(tree.T_rig)
    for name, T in tree.T_rig.items():
        assert got[name].isclose(T, mm=1e-6, deg=1e-6), name
    launch = ET.fromstring((out / "static_transforms.launch.xml").read_text())
    nodes = launch.findall("node")
    assert len(nodes) == len(tree.T_rig)
    for n in nodes:
        a = n.get("args").split()
        v = {a[i][2:]: a[i + 1] for i in range(0, len(a), 2)}
        T = tree.T(v["frame-id"], v["child-frame-id"])
        q = np.array([float(v[k]) for k in ("qx", "qy", "qz", "qw")])
        assert Pose(Pose.identity().R, [float(v[k]) * 1000 for k in "xyz"]).t == pytest.approx(T.t, abs=1e-6)
        assert abs(abs(q @ T.quaternion()) - 1) < 1e-9


def test_kalibr_chain_and_cameramodels(out, moved_rig):
    import mrcal
    tree = cad_frames(moved_rig)
    chain = yaml.safe_load((out / "kalibr_camchain.yaml").read_text())
    shorts = list(CAMERAS)
    assert sorted(chain) == ["cam0", "cam1", "cam2", "cam3"] and "T_cn_cnm1" not in chain["cam0"]
    T = Pose.identity()  # cam0 in cam0; compose T_cn_cnm1 down the chain
    for i in range(1, 4):
        M = np.array(chain[f"cam{i}"]["T_cn_cnm1"])
        M[:3, 3] *= 1000
        T = Pose.from_matrix(M) @ T
        assert T.isclose(tree.T(CAMERAS[shorts[i]], CAMERAS[shorts[0]]), mm=1e-6, deg=1e-6)
        Mi = np.array(chain[f"cam{i}"]["T_cam_imu"])
        Mi[:3, 3] *= 1000
        assert Pose.from_matrix(Mi).isclose(tree.T(CAMERAS[shorts[i]], IMU), mm=1e-6, deg=1e-6)
    for short, frame in CAMERAS.items():
        m = mrcal.cameramodel(str(out / f"{frame.removesuffix('_optical')}.cameramodel"))
        assert Pose.from_rt(m.extrinsics_rt_fromref(), metres=True).isclose(tree.T_rig[frame].inverse(), mm=1e-6)


def _trsf_pose(loc) -> Pose:
    tr = loc.wrapped.Transformation()
    M = np.array([[tr.Value(r, c) for c in range(1, 5)] for r in range(1, 4)])
    return Pose(M[:, :3], M[:, 3])


@pytest.mark.slow
def test_step_placements_match_the_extrinsics(tmp_path, moved_rig):
    """Export the STEP as the CAD tool does, read it back (OCP via cadquery), find each camera part by
    name, take its placement from the STEP, and compare with the extrinsics to 0.01 mm / 0.01 deg;
    the Boson lens barrel (a cylinder on the optical axis) is checked as a shape feature too."""
    import cadquery as cq
    out = tmp_path / "cad"
    r = subprocess.run([sys.executable, "cad/build.py", "export", "STEP", "--out", str(out),
                        *sum((["--set", s] for s in MOVED), [])], cwd=REPO, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    imported = cq.Assembly.importStep(str(out / "rig_assembly.step"))
    placed, shapes = {}, {}

    def walk(a, parent: Pose):
        T = parent @ _trsf_pose(a.loc)
        if a.obj is not None:
            placed[a.name], shapes[a.name] = T, a.obj
        for ch in a.children:
            walk(ch, T)
    walk(imported, Pose.identity())
    tree = cad_frames(moved_rig)
    from cad.bought.boson import BosonCore
    from cad.bought.zed_x import ZedX
    s = moved_rig.desc.sensors
    zed_local = ZedX.from_rig(moved_rig, s.zed_x.part).optical_frames()
    core_local = BosonCore.from_rig(moved_rig, s.thermal.part, s.thermal.lens).optical_frames()["optical"]
    expect = {"zed_x_left_optical": placed["zed_x"] @ zed_local["left"],
              "zed_x_right_optical": placed["zed_x"] @ zed_local["right"],
              "thermal_left_optical": placed["boson_left"] @ core_local,
              "thermal_right_optical": placed["boson_right"] @ core_local}
    for frame, T in expect.items():
        d = T.inverse() @ tree.T_rig[frame]
        assert np.linalg.norm(d.t) < 0.01 and d.angle_deg() < 0.01, (frame, d)
    for side in ("left", "right"):
        # the lens barrel's centre of mass, in the extrinsics' optical frame, is on the optical axis
        c = placed[f"boson_lens_{side}"].apply(np.array(shapes[f"boson_lens_{side}"].Center().toTuple()))
        local = tree.T_rig[f"thermal_{side}_optical"].inverse().apply(c)
        assert math.hypot(local[0], local[1]) < 0.01 and local[2] > 0, (side, local)
    # the ZED's two optical centres sit symmetrically about the body's centre of mass (y and z)
    cz = placed["zed_x"].apply(np.array(shapes["zed_x"].Center().toTuple()))
    mid = (tree.T_rig["zed_x_left_optical"].t + tree.T_rig["zed_x_right_optical"].t) / 2
    assert np.abs(tree.T_rig["zed_x"].inverse().apply(cz)[1:] - tree.T_rig["zed_x"].inverse().apply(mid)[1:]).max() < 0.01


@pytest.mark.slow
def test_overlapping_cameras_are_bad_input(tmp_path):
    out = tmp_path / "o"
    r = run("extrinsics", "--from-cad", "--out", str(out), "--set", "sensors.thermal.pose.xyz_mm=[0,0,-5]")
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "overlap" in lines[0] and "Traceback" not in r.stderr
    assert not out.exists()


@pytest.mark.slow
def test_pose_uncertainty_is_written_beside_the_extrinsics(out, moved_rig):
    # read back from the file: the stack-up of the same (moved) rig, and a covariance that is one
    from calibration.extrinsics.prior import stack_up_priors
    doc = yaml.safe_load((out / "pose_uncertainty.yaml").read_text())
    assert doc["rig_hash"] == moved_rig.hash
    assert doc["inputs"]["printing.printer.tolerance_mm"] == moved_rig.desc.printing.printer.tolerance_mm
    priors = stack_up_priors(moved_rig)
    for c in ("thermal_left", "thermal_right"):
        cam = doc["cameras"][c]
        assert cam["relative_to"] == "zed_x"
        for kind in ("worst_case", "rss", "sigma"):
            assert len(cam[kind]["xyz_mm"]) == 3 and len(cam[kind]["rpy_deg"]) == 3
        assert all(w >= r > s > 0 for w, r, s in zip(cam["worst_case"]["xyz_mm"] + cam["worst_case"]["rpy_deg"],
                                                     cam["rss"]["xyz_mm"] + cam["rss"]["rpy_deg"],
                                                     cam["sigma"]["xyz_mm"] + cam["sigma"]["rpy_deg"]))
        C = np.array(cam["covariance_optical"]["matrix"])
        assert C == pytest.approx(priors[c].covariance_optical, rel=1e-5, abs=1e-12)
        assert np.all(np.linalg.eigvalsh(C) > 0)
