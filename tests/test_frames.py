"""The frames module against hand-worked cases: composition, inversion, conventions."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from platform_tools.rig.frames import (R_BODY_OPTICAL, T_BODY_OPTICAL, Pose, matrix_to_quaternion,
    matrix_to_rotvec, quaternion_to_matrix, rotvec_to_matrix, rpy_to_matrix)


def test_yaw_90_maps_forward_to_left():
    # a frame yawed +90 deg about z: its x axis points along the parent's y (left in REP-103)
    T = Pose.from_xyz_rpy_deg((0, 0, 0), (0, 0, 90))
    np.testing.assert_allclose(T.apply([1, 0, 0]), [0, 1, 0], atol=1e-12)


def test_urdf_rpy_order_is_fixed_axes_xyz():
    # roll 90 then yaw 90 (fixed axes): R = Rz(90) Rx(90). Body y -> parent z by the roll, stays z after the yaw.
    T = Pose.from_xyz_rpy_deg((0, 0, 0), (90, 0, 90))
    np.testing.assert_allclose(T.apply([0, 1, 0]), [0, 0, 1], atol=1e-12)
    np.testing.assert_allclose(T.apply([1, 0, 0]), [0, 1, 0], atol=1e-12)


def test_composition_hand_worked():
    # camera 100 mm forward of the rig origin, yawed 90 deg; a point 10 mm ahead of the camera
    T_rig_cam = Pose.from_xyz_rpy_deg((100, 0, 0), (0, 0, 90))
    T_cam_pt = Pose.from_xyz_rpy_deg((10, 0, 0))
    T_rig_pt = T_rig_cam @ T_cam_pt
    np.testing.assert_allclose(T_rig_pt.t, [100, 10, 0], atol=1e-12)


def test_inverse_hand_worked():
    T = Pose.from_xyz_rpy_deg((100, 0, 0), (0, 0, 90))
    Ti = T.inverse()
    # the rig origin seen from the camera: 100 mm behind it along the rig x, which is the camera's -y
    np.testing.assert_allclose(Ti.apply([0, 0, 0]), [0, 100, 0], atol=1e-12)
    assert (T @ Ti).isclose(Pose.identity())


def test_optical_frame_convention():
    # optical z (forward) is body x; optical x (right) is body -y; optical y (down) is body -z
    np.testing.assert_allclose(T_BODY_OPTICAL.apply([0, 0, 1]), [1, 0, 0])
    np.testing.assert_allclose(T_BODY_OPTICAL.apply([1, 0, 0]), [0, -1, 0])
    np.testing.assert_allclose(T_BODY_OPTICAL.apply([0, 1, 0]), [0, 0, -1])
    # ROS writes the same rotation as rpy (-pi/2, 0, -pi/2)
    np.testing.assert_allclose(rpy_to_matrix(-np.pi / 2, 0, -np.pi / 2), R_BODY_OPTICAL, atol=1e-12)


def test_mrcal_rt_agrees_with_mrcal():
    mrcal = pytest.importorskip("mrcal")
    T = Pose.from_xyz_rpy_deg((10, -20, 30), (5, -40, 170))
    rt = T.rt()
    np.testing.assert_allclose(mrcal.R_from_r(rt[:3]), T.R, atol=1e-12)
    p = np.array([1.0, 2.0, 3.0])
    np.testing.assert_allclose(mrcal.transform_point_rt(rt, p), T.apply(p), atol=1e-9)
    np.testing.assert_allclose(Pose.from_rt(T.rt(metres=True), metres=True).t, T.t, atol=1e-9)


def test_not_a_rotation_is_refused():
    with pytest.raises(ValueError):
        Pose(np.diag([1.0, 1.0, -1.0]), np.zeros(3))


angles = st.floats(-179.0, 179.0, allow_nan=False)
pitches = st.floats(-89.0, 89.0, allow_nan=False)
coords = st.floats(-1e3, 1e3, allow_nan=False)


@pytest.mark.slow
@settings(max_examples=200, deadline=None)
@given(st.tuples(coords, coords, coords), st.tuples(angles, pitches, angles),
       st.tuples(coords, coords, coords), st.tuples(angles, pitches, angles))
def test_algebra_properties(xyz1, rpy1, xyz2, rpy2):
    a = Pose.from_xyz_rpy_deg(xyz1, rpy1)
    b = Pose.from_xyz_rpy_deg(xyz2, rpy2)
    # inverse undoes, composition is associative with points, rpy round-trips
    assert (a @ a.inverse()).isclose(Pose.identity(), mm=1e-9, deg=1e-7)
    p = np.array([1.0, -2.0, 3.0])
    np.testing.assert_allclose((a @ b).apply(p), a.apply(b.apply(p)), atol=1e-8)
    np.testing.assert_allclose(a.rpy_deg(), rpy1, atol=1e-7)
    # quaternion and rotation vector round-trip
    np.testing.assert_allclose(quaternion_to_matrix(matrix_to_quaternion(a.R)), a.R, atol=1e-9)
    np.testing.assert_allclose(rotvec_to_matrix(matrix_to_rotvec(a.R)), a.R, atol=1e-9)


def test_rotvec_near_pi():
    R = rpy_to_matrix(0, 0, np.pi)  # 180 deg about z
    r = matrix_to_rotvec(R)
    np.testing.assert_allclose(np.linalg.norm(r), np.pi, atol=1e-9)
    np.testing.assert_allclose(rotvec_to_matrix(r), R, atol=1e-9)
