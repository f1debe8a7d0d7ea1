"""The whole rig's layout: one frozen :class:`Layout` composed, by keyword, of each subsystem's
frozen value, each computed from the rig description and the subsystems it stands on (cameras ->
cooling -> camera mounts -> computer -> case -> power, handles, controls -> joints)."""
from __future__ import annotations

from dataclasses import dataclass

from platform_tools.rig import Rig
from platform_tools.rig.frames import Pose

from cad.bought.panel import PanelPart
from cad.geom import placed_bounds

from .cameras import Cameras, place_cameras
from .case import Case, place_lugs, place_shell, place_vents, port_cutout
from .compute import Compute, place_compute
from .constants import Constants
from .controls import place_controls
from .cooling import Cooling, fan_plates, place_fans
from .fits import Fits
from .handles import Handles, place_handles
from .joints import Hole, Joint, place_joints
from .mounts import CameraMounts, place_mounts, thermal_bar
from .power import Power, place_power


@dataclass(frozen=True)
class Layout:
    """Where everything is, in the rig frame (mm)."""
    rig: Rig
    c: Constants
    fits: Fits
    cameras: Cameras
    cooling: Cooling
    mounts: CameraMounts
    compute: Compute
    case: Case
    power: Power
    handles: Handles
    controls: dict[str, tuple[PanelPart, Pose]]   # node name -> (panel part, pose)
    joints: tuple[Joint, ...]

    def holes_for(self, part: str) -> tuple[Hole, ...]:
        """Every hole the joints cut into ``part`` (a node name)."""
        return tuple(h for j in self.joints for h in j.holes if h.part == part)


def build_layout(rig: Rig, c: Constants) -> Layout:
    """The layout, unchecked (:func:`cad.layout.layout` checks it first). Raises ValueError when a box
    or a stock screw cannot be made from these values."""
    fits = Fits.from_rig(rig)
    cameras = place_cameras(rig, c)
    fan_part, fans = place_fans(rig, c, fits, cameras)
    bar = thermal_bar(fits, cameras, fans)
    plates = fan_plates(c, fits, fans, bar.lo[2])
    mounts = place_mounts(rig, c, fits, cameras, bar)
    compute = place_compute(rig, c, fits, cameras, mounts, plates)
    shell = place_shell(rig, fits, cameras, fans, compute, mounts.floor_z)
    power = place_power(rig, fits, shell, compute, cameras)
    lugs = place_lugs(rig, c, shell)
    handles = place_handles(rig, c, fits, shell)
    controls = place_controls(rig, fits, shell, compute, handles)
    in_side_walls = tuple(placed_bounds(p.bounds(), pose) for name, (p, pose) in controls.items() if name == "record_button")
    case = Case(interior=shell.interior, outer=shell.outer, split_z=shell.split_z, lugs=lugs,
                port_cutout=port_cutout(fits, shell, compute),
                vents=place_vents(rig, c, fits, shell, lugs, cameras, fans, compute, power.converter_box, in_side_walls))
    cooling = Cooling(part=fan_part, fans=fans, plates=plates)
    joints = place_joints(rig, c, fits, cameras=cameras, cooling=cooling, mounts=mounts, compute=compute,
                          power=power, case=case, handles=handles)
    return Layout(rig=rig, c=c, fits=fits, cameras=cameras, cooling=cooling, mounts=mounts, compute=compute,
                  case=case, power=power, handles=handles, controls=controls,
                  joints=joints)
