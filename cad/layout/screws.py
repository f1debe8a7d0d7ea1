"""Which bought screw each joint that is not the case's own uses, from the fastener table
(cad/bought/fasteners.yaml) and the thread of the part it holds.

The case's own screw and insert are the rig's choice (``enclosure.screw``, ``enclosure.insert``);
the ZED X is held by its own camera thread (``parts.<zed>.mounting``, face bottom), and each 3010 fan
by self-tapping screws through its 2.5 mm holes.
"""
from __future__ import annotations

from platform_tools.rig import Rig
from platform_tools.rig.schema import MountingPattern

from cad.bought.fasteners import fastener_table

#: the fans' screws cut their own thread in the plate, through the fan's 2.5 mm holes
FAN_SCREW_THREAD = "M2.5"


def zed_mount_thread(rig: Rig) -> MountingPattern:
    """The ZED X's camera thread (its bottom mounting pattern)."""
    return [m for m in rig.part(rig.desc.sensors.zed_x.part).mounting if m.face.value == "bottom"][0]


def zed_screw(rig: Rig) -> str:
    """Rig part id of the screw that holds the ZED X on its shelf."""
    return fastener_table().size(zed_mount_thread(rig).thread).screw


def fan_screw() -> str:
    """Rig part id of the screw that holds each fan on its plate."""
    return fastener_table().size(FAN_SCREW_THREAD).screw
