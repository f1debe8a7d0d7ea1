"""`rig-device sros2-keys`: the keystore and one enclave per ROS service, checked by openssl (another
implementation than the one that wrote it), and through a fake `ros2` when the real tool is on PATH."""
from __future__ import annotations

import os
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from firmware import cli
from firmware.render import write
from platform_tools.rig import load_rig

OPENSSL = shutil.which("openssl")
SERIALS = ("sensors.thermal.left.serial=93588", "sensors.thermal.right.serial=93599")


def _ssl(*argv: str) -> subprocess.CompletedProcess:
    return subprocess.run([OPENSSL, *argv], capture_output=True, text=True)


@pytest.fixture()
def no_ros2(tmp_path, monkeypatch):
    """A PATH without `ros2`: the cryptography path."""
    empty = tmp_path / "empty-bin"
    empty.mkdir()
    monkeypatch.setenv("PATH", str(empty))


def _compose_enclaves(tmp_path) -> set[str]:
    rig = load_rig(None, [*SERIALS, "on_device.sros2_enclaves=true"])
    write(rig, tmp_path / "fw")
    services = yaml.safe_load((tmp_path / "fw" / "compose.yaml").read_text())["services"]
    return {s["environment"]["ROS_SECURITY_ENCLAVE_OVERRIDE"] for s in services.values()
            if "ROS_SECURITY_ENCLAVE_OVERRIDE" in (s.get("environment") or {})}


@pytest.mark.slow
@pytest.mark.skipif(OPENSSL is None, reason="openssl is not installed")
def test_the_keystore_verifies_with_openssl(tmp_path, no_ros2, capsys):
    ks = tmp_path / "keystore"
    assert cli.main(["sros2-keys", "--out", str(ks), "--json"]) == 0
    ca = ks / "public" / "ca.cert.pem"
    names = _compose_enclaves(tmp_path)          # the names compose.yaml gives the services
    assert names == {"/rgbt/zed", "/rgbt/thermal_left", "/rgbt/thermal_right", "/rgbt/recorder", "/rgbt/health_topics"}
    found = {"/" + p.parent.relative_to(ks / "enclaves").as_posix() for p in (ks / "enclaves").rglob("cert.pem")}
    assert found == names
    gov = _ssl("smime", "-verify", "-in", str(ks / "enclaves" / "governance.p7s"), "-CAfile", str(ca), "-text")
    assert gov.returncode == 0, gov.stderr
    assert gov.stdout.replace("\r\n", "\n") == (ks / "enclaves" / "governance.xml").read_text()
    assert "<id>70</id>" in gov.stdout                      # the rig's domain
    for name in names:
        d = ks.joinpath("enclaves", *name.strip("/").split("/"))
        r = _ssl("verify", "-CAfile", str(ca), str(d / "cert.pem"))
        assert r.returncode == 0 and r.stdout.strip().endswith("OK"), r.stdout + r.stderr
        subject = _ssl("x509", "-in", str(d / "cert.pem"), "-noout", "-subject", "-nameopt", "RFC2253").stdout
        assert subject.strip() == f"subject=CN={name}"
        assert _ssl("x509", "-in", str(d / "cert.pem"), "-noout", "-pubkey").stdout == \
            _ssl("pkey", "-in", str(d / "key.pem"), "-pubout").stdout      # the key is the certificate's
        perm = _ssl("smime", "-verify", "-in", str(d / "permissions.p7s"), "-CAfile", str(d / "permissions_ca.cert.pem"),
                    "-text")
        assert perm.returncode == 0, perm.stderr
        assert f"<subject_name>CN={name}</subject_name>" in perm.stdout
        assert perm.stdout.replace("\r\n", "\n") == (d / "permissions.xml").read_text()
        assert (d / "governance.p7s").resolve() == (ks / "enclaves" / "governance.p7s").resolve()
        assert stat.S_IMODE((d / "key.pem").stat().st_mode) == 0o600
    assert stat.S_IMODE((ks / "private").stat().st_mode) == 0o700


@pytest.mark.slow
@pytest.mark.skipif(OPENSSL is None, reason="openssl is not installed")
def test_a_tampered_grant_fails_openssl(tmp_path, no_ros2):
    """The verification above could fail: one edited byte of a signed grant does."""
    ks = tmp_path / "keystore"
    assert cli.main(["sros2-keys", "--out", str(ks), "-q"]) == 0
    p7s = ks / "enclaves" / "rgbt" / "recorder" / "permissions.p7s"
    p7s.write_text(p7s.read_text().replace("<default>DENY</default>", "<default>ALLOW</default>"))
    r = _ssl("smime", "-verify", "-in", str(p7s), "-CAfile", str(ks / "public" / "ca.cert.pem"), "-text")
    assert r.returncode != 0


def test_an_existing_keystore_is_never_touched(tmp_path, no_ros2, capsys):
    ks = tmp_path / "keystore"
    ks.mkdir()
    (ks / "mine").write_text("keep")
    assert cli.main(["sros2-keys", "--out", str(ks)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(ks) in err[0] and "never overwritten" in err[0]
    assert [p.name for p in ks.iterdir()] == ["mine"] and (ks / "mine").read_text() == "keep"


FAKE_ROS2 = """#!{python}
import json, os, sys
with open({log!r}, "a") as f:
    f.write(json.dumps(sys.argv[1:]) + "\\n")
if os.environ.get("FAKE_ROS2_FAIL") and sys.argv[2] == "create_enclave":
    print("ERROR: enclave failed", file=sys.stderr)
    sys.exit(1)
os.makedirs(os.path.join(sys.argv[3], *(sys.argv[4].strip("/").split("/") if len(sys.argv) > 4 else ["public"])),
            exist_ok=True)
"""


@pytest.fixture()
def fake_ros2(tmp_path, monkeypatch) -> Path:
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    log = tmp_path / "ros2.log"
    exe = bin_dir / "ros2"
    exe.write_text(FAKE_ROS2.format(python=sys.executable, log=str(log)))
    exe.chmod(0o755)
    monkeypatch.setenv("PATH", f"{bin_dir}{os.pathsep}{os.environ['PATH']}")
    return log


@pytest.mark.slow
def test_ros2_security_is_used_when_on_path(tmp_path, fake_ros2):
    import json
    ks = tmp_path / "keystore"
    assert cli.main(["sros2-keys", "--out", str(ks), "-q"]) == 0
    calls = [json.loads(ln) for ln in fake_ros2.read_text().splitlines()]
    stage = calls[0][2]
    assert calls[0][:2] == ["security", "create_keystore"] and stage != str(ks)   # into a staging folder
    assert [c[:3] for c in calls[1:]] == [["security", "create_enclave", stage]] * 5
    assert [c[3] for c in calls[1:]] == ["/rgbt/zed", "/rgbt/thermal_left", "/rgbt/thermal_right", "/rgbt/recorder",
                                         "/rgbt/health_topics"]
    assert (ks / "rgbt" / "zed").is_dir() and not Path(stage).exists()    # swapped in whole


@pytest.mark.slow
def test_a_failing_ros2_leaves_nothing(tmp_path, fake_ros2, monkeypatch, capsys):
    monkeypatch.setenv("FAKE_ROS2_FAIL", "1")
    ks = tmp_path / "keystore"
    assert cli.main(["sros2-keys", "--out", str(ks)]) == 2
    err = capsys.readouterr().err
    assert "create_enclave" in err and "enclave failed" in err
    assert not ks.exists() and not list(tmp_path.glob(".keystore.*"))
