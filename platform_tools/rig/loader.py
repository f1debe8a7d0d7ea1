"""Load `config/rig.yaml` (or another rig file) with overrides into a validated :class:`Rig`.

Every problem becomes one line naming the file and line (or the ``--set`` it came from), the key
path, the value and what was expected; :class:`RigError` carries them all.
"""
from __future__ import annotations

from pathlib import Path
from typing import Sequence

from platform_tools.rig.problems import InputProblems
from .model import Rig
from .overrides import Override, OverrideError, apply_overrides, override_for, parse_override
from .rules import check_rules
from .schema import RigDescription
from .typed import Problem
from .yamlsource import YamlSource, load_typed

#: the rig description of this repository
DEFAULT_RIG = Path(__file__).resolve().parents[2] / "config" / "rig.yaml"


class RigError(InputProblems):
    """The rig description is not valid. ``lines`` holds one message per problem."""


def _locate(problem: Problem, source: YamlSource, overrides: Sequence[Override]) -> str:
    ov = override_for(problem, overrides)
    where = f"--set {ov.text}" if ov else source.where(problem.path)
    return f"{where}: {problem}"


def load_rig(path: Path | str | None = None, overrides: Sequence[str] = ()) -> Rig:
    """Read, override, type-check and rule-check a rig description. Raises :class:`RigError`."""
    path = Path(path) if path is not None else DEFAULT_RIG
    parsed: list[Override] = []

    def prepare(data: dict) -> dict:
        parsed.extend(parse_override(o) for o in overrides)
        return apply_overrides(data, parsed, RigDescription)

    typed = load_typed(path, RigDescription, RigError, prepare=prepare, prepare_errors=(OverrideError,),
                       rules=lambda desc: check_rules(Rig(desc, path, tuple(overrides))),
                       locate=lambda problem, source: _locate(problem, source, parsed))
    return Rig(typed.value, path, tuple(overrides))
