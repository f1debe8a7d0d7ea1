"""An impossible design, as the layout finds it: each problem names the rig key (or design constant) to
change. Raised by cad/layout/constraints.py before any geometry is built, and by a layout module that
finds a part it cannot place (cad/layout/power.py: a fuse holder whose tabs take another screw)."""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class DesignProblem:
    key: str       # the rig key (or design constant) to change
    message: str

    def __str__(self) -> str:
        return f"{self.key}: {self.message}"


class DesignError(Exception):
    def __init__(self, problems: list[DesignProblem]):
        self.problems = problems
        super().__init__("\n".join(str(p) for p in problems))
