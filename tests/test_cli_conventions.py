"""Every command of every tool (both console scripts and cad/build.py) has --help; usage errors exit 2."""
from __future__ import annotations

import argparse

import pytest

from cad.build import build_parser as cad_parser
from calibration.cli import build_parser as calibrate_parser
from platform_tools.cli.main import build_parser as platform_tools_parser


def all_commands(parser: argparse.ArgumentParser, prefix=()):
    yield prefix
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from all_commands(sub, prefix + (name,))


TOOLS = {"platform_tools": ("platform_tools.cli.main", platform_tools_parser),
         "calibrate": ("calibration.cli", calibrate_parser),
         "cad/build.py": ("cad.build", cad_parser)}
CASES = [(tool, cmd) for tool, (_, build) in TOOLS.items() for cmd in all_commands(build())]


@pytest.mark.parametrize("tool,cmd", CASES, ids=[" ".join((t,) + c) for t, c in CASES])
def test_every_command_has_help(tool, cmd, capsys):
    module, build = TOOLS[tool]
    with pytest.raises(SystemExit) as exit_info:
        build().parse_args([*cmd, "--help"])
    assert exit_info.value.code == 0
    out = capsys.readouterr().out
    assert out.startswith("usage:") and len(out.splitlines()) > 3


@pytest.mark.parametrize("tool", TOOLS)
def test_unknown_command_is_usage_error(tool, capsys):
    _, build = TOOLS[tool]
    with pytest.raises(SystemExit) as exit_info:
        build().parse_args(["no-such-command"])
    assert exit_info.value.code == 2


@pytest.mark.slow
def test_console_scripts_run(platform_tools, calibrate):
    assert platform_tools("--help").returncode == 0
    assert calibrate("--help").returncode == 0
    # no subcommand: help on stderr and a usage exit
    r = platform_tools()
    assert r.returncode == 2 and "usage:" in r.stderr
