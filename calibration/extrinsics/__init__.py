"""Extrinsics of the rig: from the CAD model (:mod:`.cad`), in the formats robots use
(:mod:`.outputs`), and refined from synchronised board images (:mod:`.sets`, :mod:`.solve`)."""
from .cad import CAMERAS, IMU, FrameTree, RigGeometryError, cad_frames

__all__ = ["CAMERAS", "IMU", "FrameTree", "RigGeometryError", "cad_frames"]
