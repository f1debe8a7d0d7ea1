"""The CLI's lazy command imports (issue 15 item 6, docs/dataset.md "Speed"): ``platform_tools COMMAND`` imports
only COMMAND's module, and every parser it builds is the one the full parser has."""
from __future__ import annotations

import argparse
import json
import subprocess
import sys

import pytest

from platform_tools.cli import main


def _choices(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    (action,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return dict(action.choices)


def test_the_table_names_what_each_module_registers():
    """Each loader's module registers exactly the names the table gives it, in its order; together, in the
    order the full parser lists them."""
    listed = []
    for load, names in main.COMMAND_MODULES:
        scratch = argparse.ArgumentParser()
        load().register(scratch.add_subparsers())
        assert tuple(_choices(scratch)) == names, load
        listed += names
    assert list(_choices(main.build_parser())) == listed


@pytest.mark.parametrize("name", [n for _, names in main.COMMAND_MODULES for n in names])
def test_a_commands_parser_is_the_full_parsers(name):
    """The parser built for ``platform_tools NAME ...`` holds NAME with the same help (and its subcommands' help)
    as the full parser, and nothing of another module."""
    full, lazy = _choices(main.build_parser()), _choices(main.build_parser([name, "--help"]))
    assert name in lazy and len(lazy) < len(full)
    assert lazy[name].format_help() == full[name].format_help()
    for sub in (a for a in lazy[name]._actions if isinstance(a, argparse._SubParsersAction)):
        for sname, sp in sub.choices.items():
            assert sp.format_help() == _choices(full[name])[sname].format_help()


def test_no_command_or_an_unknown_one_builds_the_full_parser():
    for argv in ([], ["--help"], ["nope"], ["-h", "export"]):
        assert list(_choices(main.build_parser(argv))) == list(_choices(main.build_parser()))


@pytest.mark.slow
def test_export_starts_without_the_other_commands_modules():
    """A fresh interpreter building the parser of ``export`` has not imported the simulator, the Boson tools or
    the firmware (what made every command start 1.2 s of CPU late)."""
    code = ("import json, sys; from platform_tools.cli.main import build_parser; build_parser(['export']); "
            "print(json.dumps(sorted(m for m in sys.modules if m.split('.')[0] in ('firmware', 'scipy') or "
            "m.startswith(('platform_tools.sim', 'platform_tools.boson', 'platform_tools.cli.')))))")
    got = json.loads(subprocess.run([sys.executable, "-c", code], check=True, capture_output=True,
                                    text=True).stdout)
    assert got == ["platform_tools.cli.export_cmd", "platform_tools.cli.main"]


@pytest.mark.slow
def test_help_starts_without_opencv_or_the_simulators_writer():
    """A fresh interpreter building every command's parser (``platform_tools --help``) has not imported OpenCV,
    SciPy or the simulator's writer (its scene geometry and calibration targets: 0.15 s of every command's start
    before simulate_cmd imported it only when it runs)."""
    code = ("import json, sys; from platform_tools.cli.main import build_parser; build_parser(); "
            "print(json.dumps(sorted(m for m in sys.modules if m.split('.')[0] in ('cv2', 'scipy', 'calibration') or "
            "m.startswith('platform_tools.sim.writer'))))")
    got = json.loads(subprocess.run([sys.executable, "-c", code], check=True, capture_output=True,
                                    text=True).stdout)
    assert got == []
