"""Keep mrcal's C-level progress lines ("Threw out some outliers ...", CHOLMOD notes) off the user's
terminal: they go to file descriptor 2 directly, past Python's sys.stderr. Their content is in the
report anyway; pass ``enabled=False`` (the commands do with -v) to see them."""
from __future__ import annotations

import contextlib
import os
import sys
from typing import Iterator


@contextlib.contextmanager
def quiet_stderr(enabled: bool = True) -> Iterator[None]:
    if not enabled:
        yield
        return
    sys.stderr.flush()
    saved = os.dup(2)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 2)
            yield
    finally:
        sys.stderr.flush()
        os.dup2(saved, 2)
        os.close(saved)
