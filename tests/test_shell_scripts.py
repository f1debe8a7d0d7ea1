"""The repository's own shell scripts (the bootstrap that `make demo` and `make test` run, and CI's entry point) pass
shellcheck, as the generated on-device scripts do (tests/firmware/test_render.py). A comment line of bootstrap.sh
that began with the word shellcheck was read as a malformed directive, and shellcheck then checked nothing else."""
from __future__ import annotations

import shutil
import subprocess

import pytest

from tests.conftest import REPO

SCRIPTS = ("bootstrap.sh", ".ci/run")


@pytest.mark.parametrize("script", SCRIPTS)
def test_the_repositorys_shell_scripts_pass_shellcheck(script):
    if shutil.which("shellcheck") is None:
        pytest.skip("shellcheck is not installed (bootstrap.sh installs it)")
    r = subprocess.run(["shellcheck", "--shell=bash", str(REPO / script)], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stdout + r.stderr
