"""Write outputs atomically: a reader (or a crash) never sees a half-written file or folder.

- :func:`write_text` / :func:`write_bytes` / :func:`open_atomic`: a temporary file beside the target, fsync,
  ``os.replace``.
- :class:`OutputDir`: build a whole output folder in a staging folder beside it, then swap it in;
  on any error the staging folder is removed and the previous output is left as it was.
"""
from __future__ import annotations

import contextlib
import os
import secrets
import shutil
import tempfile
from pathlib import Path
from typing import BinaryIO, Iterator


class OutputError(Exception):
    """An output cannot be written (permission, not a folder, ...). ``str()`` names the path."""


def _check_parent(path: Path) -> None:
    parent = path.parent
    try:
        parent.mkdir(parents=True, exist_ok=True)
    except (PermissionError, FileExistsError, NotADirectoryError, OSError) as exc:
        raise OutputError(f"{parent}: cannot create the output folder ({exc.strerror or exc})") from None
    if not os.access(parent, os.W_OK | os.X_OK):
        raise OutputError(f"{parent}: permission denied; cannot write outputs there")


@contextlib.contextmanager
def open_atomic(path: Path | str) -> Iterator[BinaryIO]:
    """A binary file to stream into; it appears at ``path`` whole when the block ends, never otherwise.

    The temporary file's name is chosen before it is created, so an interrupt (Ctrl-C, SIGTERM turned
    into an exception) at any point, even just after the file is created, removes it: ``mkstemp``
    returns the name only after creating the file, leaving a window where nobody knew what to remove."""
    path = Path(path)
    _check_parent(path)
    tmp: Path | None = None
    try:
        while True:
            tmp = path.parent / f".{path.name}.{secrets.token_hex(8)}.tmp"
            try:
                fd = os.open(tmp, _CREATE_FLAGS, 0o600)
                break
            except FileExistsError:      # someone else's file: never removed, try another name
                tmp = None
            except OSError as exc:
                raise OutputError(f"{path}: cannot write ({exc.strerror or exc})") from None
        with os.fdopen(fd, "wb") as f:
            yield f
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        if tmp is not None:
            tmp.unlink(missing_ok=True)
        raise


_CREATE_FLAGS = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0)


def write_bytes(path: Path | str, data: bytes) -> Path:
    with open_atomic(path) as f:
        f.write(data)
    return Path(path)


def write_text(path: Path | str, text: str) -> Path:
    return write_bytes(path, text.encode("utf-8"))


class OutputDir:
    """Stage a folder of outputs and swap it in whole when the ``with`` block succeeds::

        with OutputDir(out) as stage:
            (stage / "a.yaml").write_text(...)
        # out now holds exactly what was staged; on an exception it is untouched
    """

    def __init__(self, final: Path | str):
        self.final = Path(final)
        self.stage: Path | None = None

    def __enter__(self) -> Path:
        _check_parent(self.final)
        if self.final.exists() and not self.final.is_dir():
            raise OutputError(f"{self.final}: exists and is not a folder")
        try:
            self.stage = Path(tempfile.mkdtemp(prefix=f".{self.final.name}.", suffix=".staging",
                                               dir=self.final.parent))
        except OSError as exc:
            raise OutputError(f"{self.final}: cannot write the output folder ({exc.strerror or exc})") from None
        return self.stage

    def __exit__(self, exc_type, exc, tb) -> bool:
        assert self.stage is not None
        if exc_type is not None:
            shutil.rmtree(self.stage, ignore_errors=True)
            return False
        os.chmod(self.stage, 0o755)
        old = None
        if self.final.exists():
            old = self.final.with_name(f".{self.final.name}.{os.getpid()}.old")
            os.replace(self.final, old)
        os.replace(self.stage, self.final)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
        return False
