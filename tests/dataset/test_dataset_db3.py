"""A sqlite3 rosbag2 bag (.db3, written here by rosbags' writer) is refused with one line that says what it
is and how to convert it, never called a truncated MCAP; the conversion it names works."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from platform_tools.cli.main import main
from tests.dataset import rosbags_rig


@pytest.fixture(scope="module")
def db3(tmp_path_factory, rig):
    path = tmp_path_factory.mktemp("db3") / "bag"
    truth = rosbags_rig.write(path, rosbags_rig.Spec(triggers=90, missing=(20, 21, 55), ffc={}),
                              rosbags_rig.project_layout(rig), storage="sqlite3")
    return path, truth


@pytest.mark.slow
@pytest.mark.parametrize("which", ["folder", "file"])
def test_db3_is_refused_in_one_line_naming_it(db3, tmp_path, capsys, which):
    path, _ = db3
    target = path if which == "folder" else next(path.glob("*.db3"))
    for cmd in (["sync-check", str(target)], ["export", str(target), "--out", str(tmp_path / "ds")]):
        assert main(cmd) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "sqlite3 rosbag2 bag (.db3)" in err[0] and "rosbags-convert" in err[0]
        assert "truncated" not in err[0] and "recovered" not in err[0]
    assert not (tmp_path / "ds").exists() and not list(path.glob("*.recovered.mcap"))


@pytest.mark.slow
def test_the_conversion_it_names_gives_a_bag_that_reads(db3, tmp_path, capsys):
    path, truth = db3
    out = tmp_path / "bag-mcap"
    exe = Path(sys.executable).with_name("rosbags-convert")
    subprocess.run([str(exe), "--src", str(path), "--dst", str(out), "--dst-storage", "mcap"], check=True,
                   capture_output=True)
    main(["sync-check", str(out), "--json"])
    rep = json.loads(capsys.readouterr().out)
    assert rep["streams"]["thermal_left"]["frames"] == len(truth["trigger_of"]["thermal_left"])
    assert rep["triggers"]["thermal_left"]["segments"][0]["offset_ms"] == pytest.approx(10.0, abs=0.5)
