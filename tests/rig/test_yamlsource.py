"""yamlsource composes with libyaml where PyYAML has it and with PyYAML's own parser otherwise: the data, the
line of every key and the messages for broken files must not depend on which parser ran."""
from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
import yaml

from platform_tools.rig import yamlsource
from platform_tools.rig.yamlsource import YamlSourceError, load_yaml_text

ROOT = Path(__file__).resolve().parents[2]
RIG_TEXT = (ROOT / "config" / "rig.yaml").read_text()


def repository_yaml_files() -> list[Path]:
    out = subprocess.run(["git", "ls-files", "*.yaml"], cwd=ROOT, capture_output=True, text=True, check=True)
    return [ROOT / name for name in out.stdout.split()]


def load_with(parser, monkeypatch, text: str, name: str = "f.yaml"):
    monkeypatch.setattr(yamlsource, "_FAST_PARSER", parser)
    try:
        return load_yaml_text(text, name)
    except YamlSourceError as exc:
        return str(exc)


def test_libyaml_is_the_fast_parser_here():
    # Debian's python3-yaml is built with libyaml; without it every command would read the rig ~15x slower.
    assert yaml.__with_libyaml__
    assert yamlsource._FAST_PARSER is yaml.CSafeLoader


@pytest.mark.parametrize("path", repository_yaml_files(), ids=lambda p: str(p.relative_to(ROOT)))
def test_both_parsers_read_the_same_data_and_lines(path, monkeypatch):
    text = path.read_text()
    fast = load_with(yaml.CSafeLoader, monkeypatch, text, str(path))
    pure = load_with(yaml.SafeLoader, monkeypatch, text, str(path))
    if isinstance(pure, str):  # a file yamlsource refuses (a custom tag): refused the same way
        assert fast == pure
        return
    assert fast.data == pure.data
    assert fast.lines == pure.lines
    assert len(fast.lines) > 1


BROKEN = {
    "tab": (RIG_TEXT.replace("  wall_mm: 2.4\n", "\twall_mm: 2.4\n", 1), "found character '\\t' that cannot start"),
    "unclosed_list": (RIG_TEXT.replace("  wall_mm: 2.4\n", "  wall_mm: [2.4\n", 1), "expected ',' or ']'"),
    "undefined_alias": ("a: *x\n", "undefined alias 'x'"),
    "bad_indent": (RIG_TEXT.replace("  wall_mm: 2.4\n", "    wall_mm: 2.4\n", 1), "expected <block end>"),
}


@pytest.mark.parametrize("name", sorted(BROKEN))
def test_broken_files_get_pyyamls_message_and_the_same_line(name, monkeypatch):
    text, words = BROKEN[name]
    fast = load_with(yaml.CSafeLoader, monkeypatch, text)
    pure = load_with(yaml.SafeLoader, monkeypatch, text)
    assert isinstance(fast, str) and "malformed YAML" in fast and words in fast
    assert fast == pure


def test_libyamls_message_when_only_libyaml_refuses(monkeypatch):
    class Refuses(yaml.CSafeLoader):
        def get_single_node(self):
            raise yaml.scanner.ScannerError(None, None, "libyaml's own words", yaml.Mark("f", 0, 2, 4, None, None))

    message = load_with(Refuses, monkeypatch, "a: 1\n")
    assert message == "f.yaml:3:5: malformed YAML: libyaml's own words"
