"""One cable of the rig as cad/cables.py lays it: its waypoints, its kind, what it plugs into, and how it
is bought (the data every route builder makes; the paths, sweeps and checks are cad/cables.py's)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cad.geom import Bounds, Vec3

#: a straight that must hold a bend's tangent (or two) is made this much longer than they are: 2 % to spare
BEND_SPARE = 1.02


@dataclass(frozen=True)
class Route:
    """One cable: ``points`` (rig frame, mm) from the connector it leaves to the one it plugs into."""
    name: str
    kind: str                  # a kind of the cable table
    catalogue: str | None      # the BOM entry it is bought as (None: part of a bought part's own lead)
    ends: tuple[str, str]      # the nodes it plugs into
    points: tuple[Vec3, ...]
    radius_mm: float           # the radius every bend is laid with
    plugs: tuple[bool, bool] = (True, True)   # a connector at each end (False: the part's own lead leaves it)
    #: the bodies of right-angle plugs at its ends (name, box): checked clear of every part and cable
    envelopes: tuple[tuple[str, Bounds], ...] = ()
    #: bought this much longer than its route and the kind's slack (a lead into the lid: ``LID_OPENING_SLACK_MM``)
    extra_slack_mm: float = 0.0


def _distinct(points) -> tuple[Vec3, ...]:
    """``points`` without a waypoint that repeats the one before it (a lane already at its target)."""
    out = [tuple(float(v) for v in points[0])]
    for pt in points[1:]:
        if np.linalg.norm(np.subtract(pt, out[-1])) > 1e-6:
            out.append(tuple(float(v) for v in pt))
    return tuple(out)
