"""The cable table (``cables.yaml``): diameter, minimum bend radius, plug length, stock lengths and
service slack of every kind of cable a route is swept with, and the envelopes of the right-angle plugs
that go into the Orin's rear ports. Typed and loaded as the fastener table is."""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Annotated, Literal, Mapping

from platform_tools.rig.problems import InputProblems
from platform_tools.rig.schema import Confidence
from platform_tools.rig.typed import Ge, Gt
from platform_tools.rig.yamlsource import load_typed

TABLE = Path(__file__).resolve().parent / "cables.yaml"


class CableTableError(InputProblems):
    """cad/bought/cables.yaml is not valid: one line per problem."""


@dataclass(frozen=True)
class CableKind:
    description: str
    diameter_mm: Annotated[float, Gt(0)]
    bend_factor: Annotated[float, Gt(0)]
    plug_mm: Annotated[float, Ge(0)]
    stock_lengths_mm: tuple[float, ...]
    service_slack_mm: Annotated[float, Ge(0)]
    source: str
    confidence: Confidence

    @property
    def min_bend_radius_mm(self) -> float:
        return self.bend_factor * self.diameter_mm

    def bought_length_mm(self, route_mm: float) -> float | None:
        """The stock length that holds ``route_mm`` plus the service slack (None: longer than any stock,
        or a kind cut from a reel: then the route's length plus slack, rounded up to 10 mm)."""
        need = route_mm + self.service_slack_mm
        if not self.stock_lengths_mm:
            return math.ceil(need / 10.0) * 10.0
        return next((s for s in sorted(self.stock_lengths_mm) if s >= need), None)


@dataclass(frozen=True)
class PlugEnvelope:
    """A right-angle plug in a port, as the room it takes behind the port face: ``depth_mm`` back from the
    face (the overmould), ``width_mm`` across the port, ``reach_mm`` from the port's centre to the face the
    cable leaves from (along the side it exits towards), ``height_mm``; the cable's axis leaves that face
    ``exit_depth_mm`` behind the port face, at the port's height. The overmould holds the cable's strain
    relief: the cable may bend as soon as it leaves it."""
    description: str
    depth_mm: Annotated[float, Gt(0)]
    width_mm: Annotated[float, Gt(0)]
    reach_mm: Annotated[float, Gt(0)]
    height_mm: Annotated[float, Gt(0)]
    exit_depth_mm: Annotated[float, Gt(0)]
    source: str
    confidence: Confidence


@dataclass(frozen=True)
class CableTable:
    schema_version: Literal[1]
    kinds: Mapping[str, CableKind]
    plugs: Mapping[str, PlugEnvelope]


@lru_cache(maxsize=None)
def cable_table(path: Path = TABLE) -> CableTable:
    """The cable table (read once per process). Raises :class:`CableTableError`."""
    return load_typed(path, CableTable, CableTableError).value
