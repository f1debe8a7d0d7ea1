"""Progress bars for long work, on stderr, silent when stderr is not a terminal or with -q."""
from __future__ import annotations

import sys
from typing import Iterable, TypeVar

from tqdm import tqdm

T = TypeVar("T")
_quiet = False


def set_quiet(quiet: bool) -> None:
    global _quiet
    _quiet = quiet


def progress(items: Iterable[T], *, desc: str, total: int | None = None, unit: str = "it") -> Iterable[T]:
    return tqdm(items, desc=desc, total=total, unit=unit, file=sys.stderr, leave=False,
                disable=_quiet or not sys.stderr.isatty())
