"""Read YAML strictly and remember where every key was written.

PyYAML silently keeps the last of two duplicate keys; a rig file with a key written twice is a
mistake, so it is refused here. Every value's line number is kept, keyed by its key path, so that
an error can say ``config/rig.yaml:57: sensors.thermal.baseline_mm: ...``.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Generic, Iterable, TypeVar

import yaml

from .typed import KeyPath, Problem, convert, format_path

T = TypeVar("T")


class YamlSourceError(Exception):
    """The file cannot be read or is not valid YAML. ``str()`` is one line naming the file."""


@dataclass
class YamlSource:
    path: Path
    data: Any
    lines: dict[KeyPath, int] = field(default_factory=dict)

    def line_of(self, path: KeyPath) -> int | None:
        """Line of the deepest key on ``path`` that is written in the file."""
        path = tuple(path)
        while path:
            if path in self.lines:
                return self.lines[path]
            path = path[:-1]
        return None

    def where(self, path: KeyPath) -> str:
        line = self.line_of(path)
        return f"{self.path}:{line}" if line else f"{self.path}"


#: libyaml's parser where PyYAML was built with it (Debian's python3-yaml is): it composes the rig file about
#: 15x faster than PyYAML's pure-Python parser (0.01 against 0.15 s), and every command reads the rig first.
#: Both give the same nodes, tags and line marks; values are built by PyYAML's SafeConstructor either way.
#: A file libyaml refuses is parsed again by PyYAML's parser for the message, which names more (the tab, the
#: alias) than libyaml's does.
_FAST_PARSER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def _parsed(parse: Callable, text: str) -> Any:
    """``parse(text, Loader=...)`` (yaml.compose or yaml.load) with libyaml's parser; a text libyaml refuses is
    parsed again by PyYAML's own, so that the error raised carries PyYAML's message (see :data:`_FAST_PARSER`)."""
    try:
        return parse(text, Loader=_FAST_PARSER)
    except yaml.YAMLError:
        if _FAST_PARSER is yaml.SafeLoader:
            raise
        parse(text, Loader=yaml.SafeLoader)  # raises with PyYAML's message
        raise  # PyYAML's parser accepted what libyaml refused: libyaml's message


def _compose(text: str) -> yaml.Node | None:
    return _parsed(yaml.compose, text)


def safe_load(text: str) -> Any:
    """``yaml.safe_load(text)`` through libyaml's parser (:data:`_FAST_PARSER`: a rendered firmware folder's 8
    YAML files, 54 kB, load in 24 against 202 ms), the same data; a text libyaml refuses raises PyYAML's message,
    as the rig loader's does. For YAML whose key lines nobody needs (rendered configuration): the rig and the
    tables go through :func:`load_yaml_text`, which keeps them."""
    return _parsed(yaml.load, text)


def _walk(node: yaml.Node, path: KeyPath, lines: dict, file: Path) -> Any:
    """Build Python data from a composed node, recording lines and refusing duplicate keys."""
    lines[path] = node.start_mark.line + 1
    if isinstance(node, yaml.MappingNode):
        out: dict = {}
        for key_node, value_node in node.value:
            if not isinstance(key_node, yaml.ScalarNode):
                raise YamlSourceError(f"{file}:{key_node.start_mark.line + 1}: {format_path(path)}: "
                                      f"a key must be a plain value, not a list or mapping")
            key = _scalar(key_node)
            if key in out:
                raise YamlSourceError(f"{file}:{key_node.start_mark.line + 1}: {format_path(path + (key,))}: "
                                      f"key written twice (first on line {lines[path + (key,)]})")
            out[key] = _walk(value_node, path + (key,), lines, file)
            lines[path + (key,)] = key_node.start_mark.line + 1  # errors point at the key's line
        return out
    if isinstance(node, yaml.SequenceNode):
        return [_walk(item, path + (i,), lines, file) for i, item in enumerate(node.value)]
    return _scalar(node)


def _scalar(node: yaml.ScalarNode) -> Any:
    return yaml.constructor.SafeConstructor().construct_object(node, deep=True)


def load_yaml_text(text: str, path: Path | str) -> YamlSource:
    path = Path(path)
    try:
        node = _compose(text)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        where = f"{path}:{mark.line + 1}:{mark.column + 1}" if mark else str(path)
        problem = exc.problem or exc.context or "cannot parse"
        raise YamlSourceError(f"{where}: malformed YAML: {problem}") from None
    except yaml.YAMLError as exc:
        raise YamlSourceError(f"{path}: malformed YAML: {exc}") from None
    if node is None:
        raise YamlSourceError(f"{path}: the file is empty; expected a YAML mapping")
    lines: dict[KeyPath, int] = {}
    try:
        data = _walk(node, (), lines, path)
    except yaml.constructor.ConstructorError as exc:
        mark = exc.problem_mark
        where = f"{path}:{mark.line + 1}" if mark else str(path)
        raise YamlSourceError(f"{where}: malformed YAML: {exc.problem}") from None
    return YamlSource(path, data, lines)


def load_yaml_file(path: Path | str) -> YamlSource:
    path = Path(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise YamlSourceError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise YamlSourceError(f"{path}: is a directory; expected a YAML file") from None
    except PermissionError:
        raise YamlSourceError(f"{path}: permission denied") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise YamlSourceError(f"{path}: not UTF-8 text (byte {exc.start}); expected a YAML file") from None
    return load_yaml_text(text, path)


@dataclass
class Typed(Generic[T]):
    """A typed value read from a YAML file, and the file (for locating later problems in it)."""
    value: T
    source: YamlSource


def load_typed(path: Path | str, tp: type[T], error: Callable[[list[str]], Exception], *,
               prepare: Callable[[dict], dict] | None = None, prepare_errors: tuple[type[Exception], ...] = (),
               rules: Callable[[T], Iterable[Problem]] | None = None,
               locate: Callable[[Problem, YamlSource], str] | None = None) -> Typed[T]:
    """Read ``path`` strictly, check it holds a mapping, let ``prepare`` change the data (the rig's
    ``--set`` overrides; its ``prepare_errors`` are bad input too), convert it to ``tp`` and run
    ``rules`` on the value. Any problem raises ``error(lines)``, one line per problem naming the file
    and line (``locate`` may name something else, such as the ``--set`` that caused it)."""
    path = Path(path)
    try:
        source = load_yaml_file(path)
        if not isinstance(source.data, dict):
            raise YamlSourceError(f"{path}: expected a YAML mapping at the top level, got {type(source.data).__name__}")
        data = prepare(source.data) if prepare is not None else source.data
    except (YamlSourceError, *prepare_errors) as exc:
        raise error([str(exc)]) from None
    where = locate or (lambda problem, src: f"{src.where(problem.path)}: {problem}")
    value, problems = convert(tp, data)
    if not problems and rules is not None:
        problems = list(rules(value))
    if problems:
        raise error([where(p, source) for p in problems])
    return Typed(value, source)
