"""Rigid transforms (SE(3)) and the frame conventions every part of the project shares.

Naming: ``T_a_b`` is the pose of frame b expressed in frame a; it maps points from b into a:
``p_a = T_a_b @ p_b``. Composition chains the inner names: ``T_a_c = T_a_b @ T_b_c``.

Frames:
- the rig frame follows ROS REP-103: x forward, y left, z up; lengths in mm.
- a camera *body* frame uses the same axes as the rig (x along the optical axis).
- a camera *optical* frame is x right, y down, z forward (OpenCV, mrcal, ROS ``*_optical_frame``).
  ``T_BODY_OPTICAL`` is the fixed rotation between the two.

Orientations given as roll-pitch-yaw follow URDF: fixed axes x, then y, then z, so
``R = Rz(yaw) @ Ry(pitch) @ Rx(roll)``. Rotation vectors are Rodrigues (axis * angle, radians), as
mrcal's ``rt`` (r then t) and OpenCV's ``rvec`` use.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "Pose", "rot_x", "rot_y", "rot_z", "rpy_to_matrix", "matrix_to_rpy", "rotvec_to_matrix",
    "matrix_to_rotvec", "matrix_to_quaternion", "quaternion_to_matrix", "R_BODY_OPTICAL", "T_BODY_OPTICAL",
]


def rot_x(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]], dtype=float)


def rot_y(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]], dtype=float)


def rot_z(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]], dtype=float)


def rpy_to_matrix(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """URDF roll-pitch-yaw (radians) to a rotation matrix: Rz(yaw) Ry(pitch) Rx(roll)."""
    return rot_z(yaw) @ rot_y(pitch) @ rot_x(roll)


def matrix_to_rpy(R: np.ndarray) -> tuple[float, float, float]:
    """Inverse of :func:`rpy_to_matrix` (radians); pitch in [-pi/2, pi/2]."""
    pitch = float(np.arcsin(np.clip(-R[2, 0], -1.0, 1.0)))
    if abs(abs(pitch) - np.pi / 2) < 1e-9:  # gimbal lock: put it all in yaw
        roll = 0.0
        yaw = float(np.arctan2(-R[0, 1], R[1, 1]))
    else:
        roll = float(np.arctan2(R[2, 1], R[2, 2]))
        yaw = float(np.arctan2(R[1, 0], R[0, 0]))
    return roll, pitch, yaw


def rotvec_to_matrix(r: np.ndarray) -> np.ndarray:
    """Rodrigues rotation vector (axis * angle) to a rotation matrix."""
    r = np.asarray(r, dtype=float)
    theta = float(np.linalg.norm(r))
    K = np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]], dtype=float)
    if theta < 1e-12:
        return np.eye(3) + K
    K /= theta
    return np.eye(3) + np.sin(theta) * K + (1 - np.cos(theta)) * (K @ K)


def matrix_to_rotvec(R: np.ndarray) -> np.ndarray:
    """Rotation matrix to a Rodrigues vector; exact near 0 and near pi."""
    q = matrix_to_quaternion(R)  # x y z w, w >= 0
    v, w = q[:3], q[3]
    s = float(np.linalg.norm(v))
    if s < 1e-12:
        return 2.0 * v  # small angle
    angle = 2.0 * np.arctan2(s, w)
    return v / s * angle


def matrix_to_quaternion(R: np.ndarray) -> np.ndarray:
    """Rotation matrix to a unit quaternion (x, y, z, w) with w >= 0 (ROS order)."""
    R = np.asarray(R, dtype=float)
    t = np.trace(R)
    if t > 0:
        s = np.sqrt(t + 1.0) * 2
        q = [(R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s, 0.25 * s]
    elif R[0, 0] > R[1, 1] and R[0, 0] > R[2, 2]:
        s = np.sqrt(1.0 + R[0, 0] - R[1, 1] - R[2, 2]) * 2
        q = [0.25 * s, (R[0, 1] + R[1, 0]) / s, (R[0, 2] + R[2, 0]) / s, (R[2, 1] - R[1, 2]) / s]
    elif R[1, 1] > R[2, 2]:
        s = np.sqrt(1.0 + R[1, 1] - R[0, 0] - R[2, 2]) * 2
        q = [(R[0, 1] + R[1, 0]) / s, 0.25 * s, (R[1, 2] + R[2, 1]) / s, (R[0, 2] - R[2, 0]) / s]
    else:
        s = np.sqrt(1.0 + R[2, 2] - R[0, 0] - R[1, 1]) * 2
        q = [(R[0, 2] + R[2, 0]) / s, (R[1, 2] + R[2, 1]) / s, 0.25 * s, (R[1, 0] - R[0, 1]) / s]
    q = np.array(q, dtype=float)
    q /= np.linalg.norm(q)
    return -q if q[3] < 0 else q


def quaternion_to_matrix(q: np.ndarray) -> np.ndarray:
    """Unit quaternion (x, y, z, w) to a rotation matrix."""
    x, y, z, w = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


@dataclass(frozen=True, eq=False)
class Pose:
    """A rigid transform: rotation ``R`` (3x3) and translation ``t`` (3,), translation in mm."""
    R: np.ndarray
    t: np.ndarray

    def __post_init__(self) -> None:
        R = np.array(self.R, dtype=float).reshape(3, 3)
        t = np.array(self.t, dtype=float).reshape(3)
        if not np.allclose(R @ R.T, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
            raise ValueError("Pose.R is not a rotation matrix")
        R.setflags(write=False)
        t.setflags(write=False)
        object.__setattr__(self, "R", R)
        object.__setattr__(self, "t", t)

    # construction
    @classmethod
    def identity(cls) -> "Pose":
        return cls(np.eye(3), np.zeros(3))

    @classmethod
    def from_xyz_rpy_deg(cls, xyz_mm, rpy_deg=(0.0, 0.0, 0.0)) -> "Pose":
        roll, pitch, yaw = np.radians(np.asarray(rpy_deg, dtype=float))
        return cls(rpy_to_matrix(roll, pitch, yaw), np.asarray(xyz_mm, dtype=float))

    @classmethod
    def from_matrix(cls, M: np.ndarray) -> "Pose":
        M = np.asarray(M, dtype=float)
        return cls(M[:3, :3], M[:3, 3])

    @classmethod
    def from_rt(cls, rt: np.ndarray, *, metres: bool = False) -> "Pose":
        """From mrcal's rt (Rodrigues r, then t). ``metres=True`` converts t from m to mm."""
        rt = np.asarray(rt, dtype=float)
        return cls(rotvec_to_matrix(rt[:3]), rt[3:] * (1000.0 if metres else 1.0))

    # algebra
    def __matmul__(self, other):
        if isinstance(other, Pose):
            return Pose(self.R @ other.R, self.R @ other.t + self.t)
        return self.apply(other)

    def inverse(self) -> "Pose":
        return Pose(self.R.T, -self.R.T @ self.t)

    def apply(self, points) -> np.ndarray:
        """Transform points of shape (..., 3)."""
        p = np.asarray(points, dtype=float)
        return p @ self.R.T + self.t

    def rotate(self, vectors) -> np.ndarray:
        """Rotate direction vectors of shape (..., 3) (no translation)."""
        return np.asarray(vectors, dtype=float) @ self.R.T

    # views
    def matrix(self) -> np.ndarray:
        M = np.eye(4)
        M[:3, :3] = self.R
        M[:3, 3] = self.t
        return M

    def rpy_deg(self) -> tuple[float, float, float]:
        return tuple(float(np.degrees(a)) for a in matrix_to_rpy(self.R))

    def quaternion(self) -> np.ndarray:
        return matrix_to_quaternion(self.R)

    def rt(self, *, metres: bool = False) -> np.ndarray:
        """mrcal rt: Rodrigues r, then t (in m with ``metres=True``)."""
        return np.concatenate([matrix_to_rotvec(self.R), self.t / (1000.0 if metres else 1.0)])

    def angle_deg(self) -> float:
        """The rotation angle, in degrees."""
        return float(np.degrees(np.linalg.norm(matrix_to_rotvec(self.R))))

    def isclose(self, other: "Pose", *, mm: float = 1e-6, deg: float = 1e-6) -> bool:
        d = self.inverse() @ other
        return bool(np.linalg.norm(d.t) <= mm and d.angle_deg() <= deg)

    def __repr__(self) -> str:
        x, y, z = self.t
        r, p, w = self.rpy_deg()
        return f"Pose(xyz_mm=({x:.3f}, {y:.3f}, {z:.3f}), rpy_deg=({r:.3f}, {p:.3f}, {w:.3f}))"


# A camera body frame (x forward, y left, z up) to its optical frame (x right, y down, z forward):
# the optical z axis is body x, optical x is body -y, optical y is body -z. Columns = optical axes in body.
R_BODY_OPTICAL = np.array([[0.0, 0.0, 1.0],
                           [-1.0, 0.0, 0.0],
                           [0.0, -1.0, 0.0]])
T_BODY_OPTICAL = Pose(R_BODY_OPTICAL, np.zeros(3))
