"""Bad input described as one line per problem (a rig file, a catalogue, the guide's steps ...).

Each line names where the problem is (file:line and key, or the --set it came from) and what was
expected; every command prints the lines and exits 2 (platform_tools.rig.conventions.run)."""
from __future__ import annotations

from typing import Sequence


class InputProblems(Exception):
    def __init__(self, lines: Sequence[str]):
        self.lines = list(lines)
        super().__init__("\n".join(self.lines))
