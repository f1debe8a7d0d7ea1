"""The layout of every part, computed from the rig: the one place that decides where things go.

One module per subsystem, each a frozen value built by keyword from the rig description and the
subsystems below it: :mod:`.cameras`, :mod:`.cooling`, :mod:`.mounts` (camera mounts),
:mod:`.compute`, :mod:`.case` (interior, split, lugs, port window, vents), :mod:`.power`,
:mod:`.handles`, :mod:`.controls`, :mod:`.joints` (every screw and its holes); :mod:`.rig_layout`
composes them into a :class:`Layout`, :mod:`.constraints` says what makes a layout impossible,
:mod:`.constants` holds the design's own choices and :mod:`.fits` the walls and clearances.
Everything else (part builders, the assembly, the checks) reads a :class:`Layout`.
"""
from __future__ import annotations

from platform_tools.rig import Rig

from .boson_clamp import with_boson_clamps
from .cameras import fov_half_angles_deg
from .constants import C, Constants
from .constraints import DesignError, DesignProblem, design_problems
from .handles import HandleGeometry
from .joints import Hole, Joint
from .rig_layout import Layout, build_layout

__all__ = ["C", "Constants", "DesignError", "DesignProblem", "HandleGeometry", "Hole", "Joint", "Layout",
           "design_problems", "fov_half_angles_deg", "layout"]


def layout(rig: Rig, c: Constants = C) -> Layout:
    """Compute the layout, the Bosons' retaining-plate screws among its joints (so ``params`` lists them as the
    assembly places them); raises :class:`DesignError` naming the rig keys when it cannot be made."""
    problems = design_problems(rig, c)
    if problems:
        raise DesignError(problems)
    return with_boson_clamps(build_layout(rig, c))

