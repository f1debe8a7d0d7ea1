"""The repository's layout rules (tests/layout_rules.py), applied to the project, and each rule shown to fail on a
deliberate violation in a throw-away tree, so that a rule that stopped working would be noticed."""
from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from tests import layout_rules as rules

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def project():
    return rules.scan(REPO)


# ----------------------------------------------------------------------------- the project obeys every rule
@pytest.mark.slow
def test_every_module_has_a_room(project):
    assert len(project) > 100          # the scan found the project, not an empty folder
    assert rules.unassigned(project) == []


def test_imports_run_downward(project):
    assert rules.floor_violations(project) == []


def test_the_ground_floor_imports_nothing_else_of_ours(project):
    ground = {m: mod for m, mod in project.items() if rules.room_of(m) == "platform_tools.rig"}
    assert "platform_tools.rig.loader" in ground
    climbing = {m: sorted(t for t in mod.imports if rules.room_of(t) != "platform_tools.rig")
                for m, mod in ground.items()}
    assert {m: t for m, t in climbing.items() if t} == {}


def test_no_import_cycle_between_files(project):
    assert rules.file_cycles(project) == []


def test_no_loop_between_sibling_folders(project):
    assert rules.folder_cycles(project) == []


def test_no_module_is_too_long(project):
    assert rules.long_modules(project) == []


def test_device_runtime_lives_in_firmware(project):
    assert rules.device_imports_outside(project) == []
    # the FFC status node is device code: it imports rclpy, and it is inside firmware/
    node = [m for m, mod in project.items() if "rclpy" in mod.external]
    assert node and all(m.startswith("firmware.") for m in node)


def test_device_images_install_what_the_device_imports(project):
    assert rules.install_set_leaks(project) == []


def test_device_images_vendor_exactly_the_device_install_set():
    from firmware import render
    vendored = sorted(p.replace("/", ".") for p in render.SOURCE_PACKAGES)
    assert vendored == sorted(rules.DEVICE_INSTALL)


# ----------------------------------------------------------------------------- each rule fails on a violation
def _tree(tmp_path: Path, files: dict[str, str]) -> dict:
    for rel, text in files.items():
        path = tmp_path / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(textwrap.dedent(text))
    return rules.scan(tmp_path, packages=("low", "high", "dev"))


FLOORS = {"low": 0, "high": 1, "dev": 1}


def test_an_import_up_a_floor_is_caught_even_inside_a_function(tmp_path):
    mods = _tree(tmp_path, {
        "low/__init__.py": "",
        "low/base.py": "def f():\n    from high.app import g\n    return g\n",
        "high/__init__.py": "",
        "high/app.py": "from low.base import f\ndef g(): return f\n",
    })
    found = rules.floor_violations(mods, FLOORS)
    assert found == ["low.base (floor 0, low) imports high.app (floor 1, high): up"]


def test_a_sideways_import_is_caught(tmp_path):
    mods = _tree(tmp_path, {"high/__init__.py": "", "high/a.py": "import dev.b\n",
                            "dev/__init__.py": "", "dev/b.py": ""})
    assert rules.floor_violations(mods, FLOORS) == ["high.a (floor 1, high) imports dev.b (floor 1, dev): sideways"]


def test_a_relative_import_is_resolved_before_it_is_judged(tmp_path):
    mods = _tree(tmp_path, {"high/__init__.py": "", "high/sub/__init__.py": "",
                            "high/sub/x.py": "from ...low import base\n",
                            "low/__init__.py": "", "low/base.py": "from ..high.sub import x\n"})
    assert mods["high.sub.x"].imports == {"low.base"}
    assert rules.floor_violations(mods, FLOORS) == ["low.base (floor 0, low) imports high.sub.x (floor 1, high): up"]


def test_a_module_without_a_room_is_caught(tmp_path):
    mods = _tree(tmp_path, {"low/__init__.py": "", "high/__init__.py": "", "dev/__init__.py": "",
                            "dev/x.py": ""})
    assert rules.unassigned(mods, {"low": 0, "high": 1}, namespace_roots=()) == ["dev", "dev.x"]


def test_a_file_cycle_is_caught(tmp_path):
    mods = _tree(tmp_path, {"low/__init__.py": "", "low/a.py": "from low import b\n",
                            "low/b.py": "def f():\n    import low.c\n", "low/c.py": "from .a import *\n"})
    assert rules.file_cycles(mods) == [["low.a", "low.b", "low.c"]]


def test_a_loop_between_sibling_folders_is_caught_though_no_file_cycle_exists(tmp_path):
    mods = _tree(tmp_path, {"low/__init__.py": "", "low/p/__init__.py": "", "low/q/__init__.py": "",
                            "low/p/one.py": "from low.q import two\n", "low/q/two.py": "",
                            "low/q/three.py": "from low.p import four\n", "low/p/four.py": ""})
    assert rules.file_cycles(mods) == []
    assert rules.folder_cycles(mods) == [["low.p", "low.q"]]


def test_a_root_file_may_use_its_sub_folders(tmp_path):
    mods = _tree(tmp_path, {"low/__init__.py": "", "low/p/__init__.py": "", "low/top.py": "import low.p.x\n",
                            "low/p/x.py": "from low import other\n", "low/other.py": ""})
    assert rules.folder_cycles(mods) == []


def test_a_long_module_is_caught(tmp_path):
    mods = _tree(tmp_path, {"low/__init__.py": "", "low/big.py": "x = 1\n" * 650})
    assert rules.long_modules(mods) == ["low.big: 651 lines (at most 600)"]


def test_device_code_outside_the_device_package_is_caught(tmp_path):
    mods = _tree(tmp_path, {"dev/__init__.py": "", "dev/node.py": "import rclpy\n",
                            "high/__init__.py": "", "high/gpio.py": "def f():\n    import Jetson.GPIO\n"})
    assert rules.device_imports_outside(mods, package="dev") == ["high.gpio imports Jetson"]


def test_a_device_import_of_something_not_installed_is_caught(tmp_path):
    mods = _tree(tmp_path, {"dev/__init__.py": "", "dev/run.py": "from low import base\n",
                            "low/__init__.py": "", "low/base.py": "import high.app\n",
                            "high/__init__.py": "", "high/app.py": ""})
    assert rules.install_set_leaks(mods, install=("dev", "low"), package="dev") == [
        "low.base imports high.app, which the device images do not install"]
    assert rules.install_set_leaks(mods, install=("dev", "low", "high"), package="dev") == []
