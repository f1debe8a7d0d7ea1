"""A build cache of part shapes, keyed by the part's parameters and the code that builds it.

Each spec (a frozen dataclass of plain numbers, see :mod:`cad.parts` and :mod:`cad.bought`) is turned
into a fingerprint; the key hashes that fingerprint with the source of the module that defines the
spec and of the shared geometry modules. A change of any value or of the builder's code gives a new
key, so a stale shape is never reused. Shapes are stored as OpenCascade BREP files, written
atomically; an unreadable entry is rebuilt.
"""
from __future__ import annotations

import dataclasses
import hashlib
import inspect
import json
import logging
import os
import sys
from functools import lru_cache
from pathlib import Path

import cadquery as cq
import numpy as np

from platform_tools.rig.atomic import write_bytes
from platform_tools.rig.frames import Pose

log = logging.getLogger("cad.cache")
REPO = Path(__file__).resolve().parents[1]
#: modules every builder depends on: a change there invalidates every entry
SHARED = ("cad.geom", "cad.solids", "cad.parts.common", "cad.bought.base", "cad.layout.joints", "cad.layout.handles")


def default_dir() -> Path:
    env = os.environ.get("RGBT_CAD_CACHE")
    return Path(env) if env else REPO / "build" / ".cache" / "cad"


def fingerprint(obj):
    """A JSON-able, exact description of a spec (floats by repr, poses by matrix)."""
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return {"__type__": type(obj).__qualname__,
                **{f.name: fingerprint(getattr(obj, f.name)) for f in dataclasses.fields(obj)}}
    if isinstance(obj, Pose):
        return fingerprint(obj.matrix())
    if isinstance(obj, np.ndarray):
        return [fingerprint(v) for v in obj.tolist()]
    if isinstance(obj, float):
        return repr(obj)
    if isinstance(obj, (list, tuple)):
        return [fingerprint(v) for v in obj]
    if isinstance(obj, dict):
        return {str(k): fingerprint(v) for k, v in sorted(obj.items())}
    if isinstance(obj, (int, str, bool)) or obj is None:
        return obj
    raise TypeError(f"cannot fingerprint {type(obj).__name__}")


@lru_cache(maxsize=None)
def _module_source_hash(module: str) -> str:
    mod = sys.modules.get(module)
    if mod is None:
        __import__(module)
        mod = sys.modules[module]
    return hashlib.sha256(inspect.getsource(mod).encode()).hexdigest()


def code_hash(spec) -> str:
    mods = sorted({type(spec).__module__, *SHARED})
    return hashlib.sha256("".join(_module_source_hash(m) for m in mods).encode()).hexdigest()


def key(spec) -> str:
    text = json.dumps(fingerprint(spec), sort_keys=True) + code_hash(spec)
    return hashlib.sha256(text.encode()).hexdigest()[:32]


class ShapeCache:
    """Shapes by spec: memory first, then the BREP folder, then ``spec.build()``."""

    def __init__(self, folder: Path | None = None, enabled: bool = True):
        self.folder = Path(folder) if folder else default_dir()
        self.enabled = enabled
        self.memory: dict[str, cq.Shape] = {}
        self.hits = self.misses = 0

    def get(self, spec) -> cq.Shape:
        k = key(spec)
        if k in self.memory:
            return self.memory[k]
        path = self.folder / f"{type(spec).__name__}-{k}.brep"
        shape = None
        if self.enabled and path.exists():
            try:
                shape = cq.Shape.importBrep(str(path))
                self.hits += 1
            except Exception:  # a damaged entry is rebuilt below
                log.warning("cache entry %s is unreadable; rebuilding", path)
                shape = None
        if shape is None:
            self.misses += 1
            shape = spec.build()
            if self.enabled:
                try:
                    import io
                    buf = io.BytesIO()
                    shape.exportBrep(buf)
                    write_bytes(path, buf.getvalue())
                except Exception as exc:  # the cache is an optimisation: never fail a build on it
                    log.warning("cannot write cache entry %s: %s", path, exc)
        self.memory[k] = shape
        return shape
