"""Plain data (from YAML) into typed, frozen dataclasses, with every error named by its key path.

The rig description is a tree of frozen dataclasses whose fields carry their type and, through
``typing.Annotated``, their unit and range::

    baseline_mm: Annotated[float, Unit("mm"), Gt(0)]

``convert(cls, data)`` walks the data and the type together. It never stops at the first problem:
it returns the value (or None) and a list of :class:`Problem`, one per bad value, each with the key
path (``sensors.thermal.pose.xyz_mm[2]``), the value found and what was expected.
"""
from __future__ import annotations

import collections.abc
import dataclasses
import difflib
import enum
import types
import typing
from dataclasses import dataclass
from typing import Annotated, Any, Literal, Mapping, Union, get_args, get_origin, get_type_hints

__all__ = [
    "Unit", "Gt", "Ge", "Lt", "Le", "Problem", "KeyPath", "convert", "to_data", "field_names",
    "closest",
]


# ----------------------------------------------------------------------------- constraints
@dataclass(frozen=True)
class Unit:
    """The unit a number is in (documentation and messages only; values are stored in it)."""
    symbol: str


@dataclass(frozen=True)
class Gt:
    bound: float

    def ok(self, v: float) -> bool:
        return v > self.bound

    def describe(self) -> str:
        return f"> {self.bound:g}"


@dataclass(frozen=True)
class Ge:
    bound: float

    def ok(self, v: float) -> bool:
        return v >= self.bound

    def describe(self) -> str:
        return f">= {self.bound:g}"


@dataclass(frozen=True)
class Lt:
    bound: float

    def ok(self, v: float) -> bool:
        return v < self.bound

    def describe(self) -> str:
        return f"< {self.bound:g}"


@dataclass(frozen=True)
class Le:
    bound: float

    def ok(self, v: float) -> bool:
        return v <= self.bound

    def describe(self) -> str:
        return f"<= {self.bound:g}"


_BOUNDS = (Gt, Ge, Lt, Le)


# ----------------------------------------------------------------------------- key paths
KeyPath = tuple  # of str (mapping keys) and int (sequence indices)


def format_path(path: KeyPath) -> str:
    out = ""
    for part in path:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += ("." if out else "") + str(part)
    return out or "(top level)"


@dataclass(frozen=True)
class Problem:
    """One thing wrong with the data: where, what was found, what was expected."""
    path: KeyPath
    message: str

    @property
    def where(self) -> str:
        return format_path(self.path)

    def __str__(self) -> str:
        return f"{self.where}: {self.message}"


def closest(word: str, choices: typing.Iterable[str]) -> str | None:
    found = difflib.get_close_matches(word, list(choices), n=1, cutoff=0.5)
    return found[0] if found else None


def _show(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _kind(value: Any) -> str:
    if value is None:
        return "nothing (null)"
    return {bool: "a boolean", int: "an integer", float: "a number", str: "a string",
            list: "a list", dict: "a mapping"}.get(type(value), type(value).__name__)


# ----------------------------------------------------------------------------- conversion
def _split_annotated(tp: Any) -> tuple[Any, tuple]:
    if get_origin(tp) is Annotated:
        base, *meta = get_args(tp)
        return base, tuple(meta)
    return tp, ()


def _unit_of(meta: tuple) -> str | None:
    return next((m.symbol for m in meta if isinstance(m, Unit)), None)


def _describe(tp: Any, meta: tuple = ()) -> str:
    """What a value of this type looks like, in words, for 'expected ...'."""
    tp, more = _split_annotated(tp)
    meta = meta + more
    unit = _unit_of(meta)
    bounds = " and ".join(m.describe() for m in meta if isinstance(m, _BOUNDS))
    origin = get_origin(tp)
    if tp is float:
        text = "a number" + (f" in {unit}" if unit else "")
    elif tp is int:
        text = "an integer" + (f" in {unit}" if unit else "")
    elif tp is str:
        text = "a string"
    elif tp is bool:
        text = "true or false"
    elif isinstance(tp, type) and issubclass(tp, enum.Enum):
        text = "one of " + ", ".join(str(m.value) for m in tp)
    elif origin is Literal:
        text = "one of " + ", ".join(str(a) for a in get_args(tp))
    elif origin is tuple:
        args = get_args(tp)
        if len(args) == 2 and args[1] is Ellipsis:
            text = f"a list of {_describe(args[0])}"
        else:
            text = f"a list of {len(args)} × {_describe(args[0], meta)}"
            bounds = ""
    elif origin in (dict, collections.abc.Mapping) or tp is dict:
        text = "a mapping"
    elif dataclasses.is_dataclass(tp):
        text = f"a mapping with keys {', '.join(field_names(tp))}"
    elif origin in (Union, types.UnionType):
        text = " or ".join(_describe(a) for a in get_args(tp) if a is not type(None))
    else:
        text = str(tp)
    return f"{text} {bounds}".strip()


def field_names(cls: type) -> list[str]:
    return [f.name for f in dataclasses.fields(cls)]


def convert(tp: Any, data: Any, path: KeyPath = ()) -> tuple[Any, list[Problem]]:
    """Convert ``data`` to ``tp``. Returns (value or None, problems)."""
    problems: list[Problem] = []
    value = _convert(tp, data, path, (), problems)
    return value, problems


def _convert(tp: Any, data: Any, path: KeyPath, meta: tuple, problems: list[Problem]) -> Any:
    tp, more = _split_annotated(tp)
    meta = meta + more
    origin = get_origin(tp)

    def bad(message: str) -> None:
        problems.append(Problem(path, message))

    def expected() -> str:
        return f"got {_show(data)} ({_kind(data)}); expected {_describe(tp, meta)}"

    # Optional / unions
    if origin in (Union, types.UnionType):
        args = get_args(tp)
        if data is None and type(None) in args:
            return None
        options = [a for a in args if a is not type(None)]
        if len(options) == 1:
            return _convert(options[0], data, path, meta, problems)
        for option in options:
            trial: list[Problem] = []
            value = _convert(option, data, path, meta, trial)
            if not trial:
                return value
        bad(expected())
        return None

    if data is None and tp is not type(None):
        bad(f"is missing a value; expected {_describe(tp, meta)}")
        return None

    if tp is bool:
        if not isinstance(data, bool):
            bad(expected())
            return None
        return data

    if tp in (int, float):
        ok_types = (int,) if tp is int else (int, float)
        if isinstance(data, bool) or not isinstance(data, ok_types):
            if tp is int and isinstance(data, float) and data.is_integer():
                data = int(data)
            else:
                bad(expected())
                return None
        value = tp(data)
        if tp is float and value != value:  # NaN
            bad(expected())
            return None
        for m in meta:
            if isinstance(m, _BOUNDS) and not m.ok(value):
                unit = _unit_of(meta)
                bad(f"got {value:g}{(' ' + unit) if unit else ''}; expected {_describe(tp, meta)}")
                return None
        return value

    if tp is str:
        if not isinstance(data, str):
            bad(expected())
            return None
        if not data.strip():
            bad("is empty; expected a non-empty string")
            return None
        return data

    if isinstance(tp, type) and issubclass(tp, enum.Enum):
        for member in tp:
            if member.value == data:
                return member
        hint = closest(str(data), [str(m.value) for m in tp])
        bad(expected() + (f" (did you mean {hint!r}?)" if hint else ""))
        return None

    if origin is Literal:
        if data in get_args(tp):
            return data
        hint = closest(str(data), [str(a) for a in get_args(tp)])
        bad(expected() + (f" (did you mean {hint!r}?)" if hint else ""))
        return None

    if origin is tuple:
        if not isinstance(data, (list, tuple)):
            bad(expected())
            return None
        args = get_args(tp)
        if len(args) == 2 and args[1] is Ellipsis:
            item_types = [args[0]] * len(data)
        else:
            if len(data) != len(args):
                bad(f"has {len(data)} items; expected {_describe(tp, meta)}")
                return None
            item_types = list(args)
        # constraints written on a fixed-length tuple apply to each of its numbers
        items = [_convert(t, d, path + (i,), meta if not (len(args) == 2 and args[1] is Ellipsis) else (),
                          problems) for i, (t, d) in enumerate(zip(item_types, data))]
        return tuple(items)

    if origin in (dict, collections.abc.Mapping):
        if not isinstance(data, dict):
            bad(expected())
            return None
        key_tp, val_tp = get_args(tp)
        out = {}
        for key, item in data.items():
            if not isinstance(key, str):
                problems.append(Problem(path + (str(key),), f"key {key!r} is not a string"))
                continue
            out[key] = _convert(val_tp, item, path + (key,), (), problems)
        return types.MappingProxyType(out)

    if dataclasses.is_dataclass(tp):
        if not isinstance(data, dict):
            bad(expected())
            return None
        hints = get_type_hints(tp, include_extras=True)
        fields = {f.name: f for f in dataclasses.fields(tp) if f.init}
        kwargs = {}
        for key in data:
            if key not in fields:
                hint = closest(str(key), fields)
                problems.append(Problem(path + (str(key),), "unknown key" + (
                    f" (did you mean {hint!r}?)" if hint else f"; expected one of {', '.join(fields)}")))
        failed = False
        for name, f in fields.items():
            if name in data:
                before = len(problems)
                value = _convert(hints[name], data[name], path + (name,), (), problems)
                if len(problems) > before:
                    failed = True
                kwargs[name] = value
            elif f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
                problems.append(Problem(path + (name,),
                                        f"is missing; expected {_describe(hints[name])}"))
                failed = True
        if failed:
            return None
        # bounds written on a dataclass with a 'value' field (a sourced number) apply to the value
        value_bounds = [m for m in meta if isinstance(m, _BOUNDS)]
        if value_bounds and "value" in fields:
            v = kwargs.get("value")
            for m in value_bounds:
                if v is not None and not m.ok(v):
                    unit = _unit_of(meta)
                    problems.append(Problem(path + ("value",), f"got {v:g}{(' ' + unit) if unit else ''}; "
                                                               f"expected a number {m.describe()}"))
                    return None
        try:
            return tp(**kwargs)
        except (TypeError, ValueError) as exc:  # __post_init__ checks
            bad(str(exc))
            return None

    if tp is Any:
        return data
    raise TypeError(f"typed.convert does not support {tp!r} (at {format_path(path)})")


# ----------------------------------------------------------------------------- back to data
def to_data(value: Any) -> Any:
    """Dataclasses, enums, mappings and tuples back into plain YAML/JSON data."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: to_data(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, enum.Enum):
        return value.value
    if isinstance(value, (dict, types.MappingProxyType)):
        return {k: to_data(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_data(v) for v in value]
    if hasattr(value, "tolist"):  # numpy
        return value.tolist()
    return value
