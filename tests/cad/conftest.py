import pytest


@pytest.fixture(scope="session")
def asm(rig):
    from cad.assembly import build
    return build(rig)


@pytest.fixture(scope="session")
def results(asm):
    from cad.checks import run_checks
    return {r.name: r for r in run_checks(asm)}
