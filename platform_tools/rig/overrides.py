"""Command-line overrides of the rig description: ``--set sensors.thermal.baseline_mm=150``.

An override names a key path (dots between keys, ``[i]`` for list items) and a YAML value. It may
change any value the file holds, and set an optional key the file leaves out; it may not invent
keys: an unknown key is refused with the closest valid path suggested.
"""
from __future__ import annotations

import collections.abc
import copy
import dataclasses
import re
import types
import typing
from dataclasses import dataclass
from typing import Any, Union, get_args, get_origin, get_type_hints

import yaml

from .typed import KeyPath, Problem, closest, format_path

_TOKEN = re.compile(r"([A-Za-z0-9_\-]+)|\[(\d+)\]")


@dataclass(frozen=True)
class Override:
    text: str          # as the user wrote it
    path: KeyPath
    value: Any


class OverrideError(Exception):
    """An override cannot be parsed or names no key. ``str()`` is one line."""


def parse_path(text: str, whole: str | None = None) -> KeyPath:
    """``a.b[2].c`` -> ("a", "b", 2, "c"). ``whole`` is the override as written, for messages."""
    whole = whole or text
    parts: list = []
    pos = 0
    while pos < len(text):
        if text[pos] == "." and parts and pos + 1 < len(text):
            pos += 1
        m = _TOKEN.match(text, pos)
        if not m:
            raise OverrideError(f"--set {whole}: cannot read the key path at {text[pos:]!r}; "
                                f"expected keys joined by dots, e.g. sensors.thermal.baseline_mm")
        parts.append(m.group(1) if m.group(1) is not None else int(m.group(2)))
        pos = m.end()
    if not parts or isinstance(parts[0], int):
        raise OverrideError(f"--set {whole}: expected a key path such as sensors.thermal.baseline_mm")
    return tuple(parts)


def parse_override(text: str) -> Override:
    if "=" not in text:
        raise OverrideError(f"--set {text}: expected KEY=VALUE, e.g. sensors.thermal.baseline_mm=150")
    key, raw = text.split("=", 1)
    path = parse_path(key.strip(), text)
    try:
        value = yaml.safe_load(raw) if raw.strip() else None
    except yaml.YAMLError:
        raise OverrideError(f"--set {text}: the value {raw!r} is not valid YAML") from None
    return Override(text, path, value)


def _unwrap(tp: Any) -> Any:
    while True:
        origin = get_origin(tp)
        if origin is typing.Annotated:
            tp = get_args(tp)[0]
        elif origin in (Union, types.UnionType):
            options = [a for a in get_args(tp) if a is not type(None)]
            if len(options) != 1:
                return tp
            tp = options[0]
        else:
            return tp


def apply_overrides(data: Any, overrides: typing.Sequence[Override], schema: type) -> Any:
    """Return a copy of ``data`` with the overrides applied. Raises :class:`OverrideError`."""
    data = copy.deepcopy(data)
    for ov in overrides:
        _apply_one(data, ov, schema)
    return data


def _apply_one(data: Any, ov: Override, schema: type) -> None:
    node, tp = data, schema
    for depth, key in enumerate(ov.path):
        last = depth == len(ov.path) - 1
        tp = _unwrap(tp)
        here = format_path(ov.path[:depth + 1])
        origin = get_origin(tp)
        if dataclasses.is_dataclass(tp):
            names = [f.name for f in dataclasses.fields(tp)]
            if not isinstance(key, str) or key not in names:
                raise OverrideError(_unknown(ov, depth, names))
            child_tp = get_type_hints(tp, include_extras=True)[key]
        elif origin in (dict, collections.abc.Mapping):
            existing = list(node.keys()) if isinstance(node, dict) else []
            if not isinstance(key, str) or key not in existing:
                raise OverrideError(_unknown(ov, depth, existing))
            child_tp = get_args(tp)[1]
        elif origin is tuple:
            if not isinstance(key, int):
                raise OverrideError(f"--set {ov.text}: {here}: expected a list index like [0]")
            length = len(node) if isinstance(node, list) else 0
            if key >= length:
                raise OverrideError(f"--set {ov.text}: {here}: index {key} is out of range "
                                    f"({format_path(ov.path[:depth])} has {length} items)")
            args = get_args(tp)
            child_tp = args[0] if (len(args) == 2 and args[1] is Ellipsis) else args[key]
        else:
            raise OverrideError(f"--set {ov.text}: {format_path(ov.path[:depth])} is a single value; "
                                f"it has no key {key!r}")
        if last:
            if isinstance(node, (dict, list)):
                node[key] = ov.value
            else:
                raise OverrideError(f"--set {ov.text}: {format_path(ov.path[:depth])} is not set in the file")
            return
        if isinstance(node, dict):
            if key not in node or node[key] is None:
                node[key] = {}
            node = node[key]
        elif isinstance(node, list):
            node = node[key]
        else:
            raise OverrideError(f"--set {ov.text}: {format_path(ov.path[:depth])} is not a mapping in the file")
        tp = child_tp


def _unknown(ov: Override, depth: int, valid: typing.Iterable[str]) -> str:
    key = ov.path[depth]
    hint = closest(str(key), [str(v) for v in valid])
    prefix = ov.path[:depth]
    msg = f"--set {ov.text}: unknown key {format_path(ov.path[:depth + 1])}"
    if hint:
        msg += f" (did you mean {format_path(prefix + (hint,))}?)"
    else:
        msg += f"; {format_path(prefix)} has keys {', '.join(map(str, valid))}"
    return msg


def override_for(problem: Problem, overrides: typing.Sequence[Override]) -> Override | None:
    """The override a problem comes from, if any (the longest whose path is a prefix of it)."""
    best = None
    for ov in overrides:
        n = len(ov.path)
        if tuple(problem.path[:n]) == ov.path and (best is None or n > len(best.path)):
            best = ov
    return best
