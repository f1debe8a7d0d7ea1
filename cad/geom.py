"""Geometry in numbers shared by the layout and the part builders: axis-aligned boxes (:class:`Bounds`), boxes
placed by a :class:`~platform_tools.rig.frames.Pose`, poses made from a position and angles or an axis.

No B-rep here (cad/solids.py holds the CadQuery helpers): the layout, its limits and the commands that need only
them (``params``, a refused ``--set``) run without loading CadQuery and OpenCascade (3 to 4 s of imports).
Every builder works in millimetres in its part's own frame (x forward, y left, z up, as the rig).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from platform_tools.rig.frames import Pose

Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class Bounds:
    """An axis-aligned box by its minimum and maximum corners (mm)."""
    lo: Vec3
    hi: Vec3

    def __post_init__(self) -> None:
        if any(h <= l for l, h in zip(self.lo, self.hi)):
            raise ValueError(f"empty bounds {self.lo} .. {self.hi}")

    @classmethod
    def centred(cls, centre: Vec3, size: Vec3) -> "Bounds":
        return cls(tuple(c - s / 2 for c, s in zip(centre, size)), tuple(c + s / 2 for c, s in zip(centre, size)))

    @property
    def size(self) -> Vec3:
        return tuple(h - l for l, h in zip(self.lo, self.hi))

    @property
    def centre(self) -> Vec3:
        return tuple((h + l) / 2 for l, h in zip(self.lo, self.hi))

    def grown(self, d: float) -> "Bounds":
        return Bounds(tuple(v - d for v in self.lo), tuple(v + d for v in self.hi))

    def overlaps(self, other: "Bounds", eps: float = 0.0) -> bool:
        return all(a_lo < b_hi - eps and b_lo < a_hi - eps
                   for a_lo, a_hi, b_lo, b_hi in zip(self.lo, self.hi, other.lo, other.hi))

    def gap_to(self, other: "Bounds") -> float:
        """Largest axis gap between two boxes (negative when they overlap on every axis)."""
        return max(max(b_lo - a_hi, a_lo - b_hi) for a_lo, a_hi, b_lo, b_hi
                   in zip(self.lo, self.hi, other.lo, other.hi))


def placed_bounds(local: Bounds, pose: Pose) -> Bounds:
    """The axis-aligned box (rig frame, mm) around ``local`` (a box in a part's frame) placed at ``pose``."""
    corners = np.array([[x, y, z] for x in (local.lo[0], local.hi[0]) for y in (local.lo[1], local.hi[1])
                        for z in (local.lo[2], local.hi[2])])
    p = pose.apply(corners)
    return Bounds(tuple(p.min(axis=0)), tuple(p.max(axis=0)))


def pose_xyz(x: float, y: float, z: float, rpy_deg: Vec3 = (0.0, 0.0, 0.0)) -> Pose:
    return Pose.from_xyz_rpy_deg((x, y, z), rpy_deg)


def pose_axis_z_to(direction: Vec3, origin: Vec3) -> Pose:
    """A pose whose z axis points along ``direction`` (a unit axis vector), placed at ``origin``."""
    d = np.asarray(direction, dtype=float)
    d /= np.linalg.norm(d)
    ref = np.array([1.0, 0, 0]) if abs(d[0]) < 0.9 else np.array([0, 1.0, 0])
    x = np.cross(ref, d)
    x /= np.linalg.norm(x)
    y = np.cross(d, x)
    return Pose(np.column_stack([x, y, d]), np.asarray(origin, dtype=float))
