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


def rendered_firmware_yaml(tmp_path_factory) -> list[Path]:
    from firmware.render import write
    from platform_tools.rig import load_rig
    out = tmp_path_factory.mktemp("fw") / "fw"
    write(load_rig(), out)
    return sorted(out.rglob("*.yaml"))


def test_safe_load_reads_what_pyyaml_reads(tmp_path_factory):
    """safe_load (libyaml) gives yaml.safe_load's data for every YAML file of the repository and of a rendered
    firmware folder, the files it reads."""
    files = repository_yaml_files() + rendered_firmware_yaml(tmp_path_factory)
    assert any(f.name == "compose.yaml" for f in files)
    for path in files:
        text = path.read_text()
        try:
            pure = yaml.safe_load(text)
        except yaml.YAMLError as exc:        # a custom tag: refused both ways, with the same words
            with pytest.raises(yaml.YAMLError) as got:
                yamlsource.safe_load(text)
            assert str(got.value) == str(exc), path
            continue
        assert yamlsource.safe_load(text) == pure, path


@pytest.mark.parametrize("name", sorted(BROKEN))
def test_safe_load_refuses_a_broken_text_with_pyyamls_message(name):
    text, words = BROKEN[name]
    with pytest.raises(yaml.YAMLError) as pure:
        yaml.safe_load(text)
    with pytest.raises(yaml.YAMLError) as fast:
        yamlsource.safe_load(text)
    assert words in str(fast.value) and str(fast.value) == str(pure.value)
