"""The result of one check, shared by every command that runs checks (doctor's pre-flight, the
firmware checks): a name, a status (ok / failed / skipped: a validator that is not installed is
skipped, never passed) and a detail a user can act on."""
from __future__ import annotations

from dataclasses import dataclass

OK, FAILED, SKIPPED = "ok", "failed", "skipped"


@dataclass(frozen=True)
class Check:
    name: str
    status: str
    detail: str

    def to_dict(self) -> dict:
        return {"name": self.name, "status": self.status, "detail": self.detail}
