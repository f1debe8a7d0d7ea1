"""`platform_tools firmware pin --refresh` against a local server speaking the Docker Registry HTTP API v2
(401 + Bearer challenge, token endpoint, manifest with Docker-Content-Digest) and serving an archive;
the archive's hash is checked with coreutils' sha256sum, the edit of the rig file line by line."""
from __future__ import annotations

import difflib
import hashlib
import http.server
import json
import shutil
import socket
import subprocess
import threading
import urllib.parse
from pathlib import Path

import pytest
import yaml

from firmware import pin, privilege
from firmware.render import write
from platform_tools.cli.main import main
from platform_tools.rig import DEFAULT_RIG, load_rig

REPOS = {"nvidia/l4t-jetpack": "r36.4.0", "library/ros": "humble-ros-base-jammy"}
ARCHIVE_PATH = "/zedsdk/5.0/l4t36.4/jetsons"
ARCHIVE = bytes(range(256)) * 12_289          # 3 MB and a bit: more than one read block


def _manifest(repo: str) -> bytes:
    return json.dumps({"schemaVersion": 2, "mediaType": "application/vnd.oci.image.index.v1+json",
                       "manifests": [{"mediaType": "application/vnd.oci.image.manifest.v1+json",
                                      "digest": "sha256:" + hashlib.sha256(repo.encode()).hexdigest(), "size": 1,
                                      "platform": {"architecture": "arm64", "os": "linux"}}]}).encode()


class Registry(http.server.BaseHTTPRequestHandler):
    lie = False          # send a Docker-Content-Digest that is not the manifest's
    seen: list = []

    def log_message(self, *args):
        pass

    def _send(self, code: int, body: bytes, **headers) -> None:
        self.send_response(code)
        for k, v in headers.items():
            self.send_header(k.replace("_", "-"), v)
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)

    def do_GET(self):
        url = urllib.parse.urlsplit(self.path)
        self.seen.append((url.path, dict(urllib.parse.parse_qsl(url.query)), dict(self.headers)))
        port = self.server.server_address[1]
        if url.path == "/token":
            scope = dict(urllib.parse.parse_qsl(url.query)).get("scope", "")
            return self._send(200, json.dumps({"token": f"tok-{scope}"}).encode())
        if url.path == ARCHIVE_PATH:
            return self._send(200, ARCHIVE)
        for repo, tag in REPOS.items():
            if url.path == f"/v2/{repo}/manifests/{tag}":
                scope = f"repository:{repo}:pull"
                if self.headers.get("Authorization") != f"Bearer tok-{scope}":
                    return self._send(401, b"{}", WWW_Authenticate=f'Bearer realm="http://127.0.0.1:{port}/token",'
                                                                  f'service="test-registry",scope="{scope}"')
                body = _manifest(repo)
                digest = "sha256:" + hashlib.sha256(body if not self.lie else b"other").hexdigest()
                return self._send(200, body, Docker_Content_Digest=digest,
                                  Content_Type="application/vnd.oci.image.index.v1+json")
        self._send(404, b"not found")


@pytest.fixture()
def registry():
    Registry.seen = []
    Registry.lie = False
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Registry)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    yield f"http://127.0.0.1:{server.server_address[1]}"
    server.shutdown()
    server.server_close()


@pytest.fixture()
def rig_file(tmp_path) -> Path:
    f = tmp_path / "rig.yaml"
    shutil.copy(DEFAULT_RIG, f)
    return f


def _mirrors(url: str) -> list[str]:
    return [a for host in ("nvcr.io", "registry-1.docker.io", "download.stereolabs.com")
            for a in ("--mirror", f"{host}={url}")]


def test_image_references_as_registries_name_them():
    assert pin.ImageRef.parse("nvcr.io/nvidia/l4t-jetpack:r36.4.0") == \
        pin.ImageRef("nvcr.io", "nvidia/l4t-jetpack", "r36.4.0")
    assert pin.ImageRef.parse("ros:humble-ros-base-jammy@sha256:ab") == \
        pin.ImageRef("registry-1.docker.io", "library/ros", "humble-ros-base-jammy")
    assert pin.ImageRef.parse("localhost:5000/me/img") == pin.ImageRef("localhost:5000", "me/img", "latest")


def test_the_edit_changes_only_the_values():
    text = "a:\n  # why b\n  b: null   # keep me\n  c: 3\nd: [1, 2]\n"
    new = pin.set_values(text, {("a", "b"): "sha256:00ff"})
    assert new == 'a:\n  # why b\n  b: "sha256:00ff"   # keep me\n  c: 3\nd: [1, 2]\n'
    with pytest.raises(pin.PinError, match="a.x: no such key"):
        pin.set_values(text, {("a", "x"): "v"})


@pytest.mark.slow
def test_refresh_writes_the_registry_digests_and_the_archive_hash(registry, rig_file, tmp_path, capsys):
    before = rig_file.read_text()
    assert main(["firmware", "pin", "--refresh", "--rig", str(rig_file), "--json", *_mirrors(registry)]) == 0
    after = rig_file.read_text()
    # the archive's hash, by another implementation: coreutils
    (tmp_path / "archive").write_bytes(ARCHIVE)
    sha = subprocess.run(["sha256sum", str(tmp_path / "archive")], capture_output=True, text=True).stdout.split()[0]
    want = {"l4t_jetpack_digest": "sha256:" + hashlib.sha256(_manifest("nvidia/l4t-jetpack")).hexdigest(),
            "ros_digest": "sha256:" + hashlib.sha256(_manifest("library/ros")).hexdigest(), "zed_sdk_sha256": sha}
    changed = [ln for ln in difflib.ndiff(before.splitlines(), after.splitlines()) if ln[:1] in "+-"]
    assert len(changed) == 6, changed                                      # three lines, nothing else
    assert "# sha256sum of the installer" in next(ln for ln in changed if ln.startswith("+") and "zed_sdk" in ln)
    od = yaml.safe_load(after)["on_device"]
    assert od["base_images"] == {k: want[k] for k in ("l4t_jetpack_digest", "ros_digest")}
    assert od["downloads"]["zed_sdk_sha256"] == want["zed_sdk_sha256"]
    # the registry conversation: a challenge answered with the token it named, the index asked for
    tokens = [q for p, q, _ in Registry.seen if p == "/token"]
    assert {t["scope"] for t in tokens} == {f"repository:{r}:pull" for r in REPOS}
    assert all(t["service"] == "test-registry" for t in tokens)
    manifests = [h for p, _, h in Registry.seen if "/manifests/" in p]
    assert all("application/vnd.oci.image.index.v1+json" in h["Accept"] for h in manifests)
    # the render pins the FROM lines by digest, and the rule that guards it passes
    rig = load_rig(rig_file)
    write(rig, tmp_path / "fw")
    zed = (tmp_path / "fw" / "docker" / "zed" / "Dockerfile").read_text()
    assert f"ARG BASE_IMAGE=nvcr.io/nvidia/l4t-jetpack:r36.4.0@{want['l4t_jetpack_digest']}" in zed
    assert f"ARG ZED_SDK_SHA256={sha}" in zed
    assert privilege.check_downloads(tmp_path / "fw", rig).status == "ok"
    capsys.readouterr()
    assert main(["firmware", "pin", "--rig", str(rig_file)]) == 0          # nothing left unset


@pytest.mark.slow
def test_a_digest_header_that_lies_is_refused(registry, rig_file, capsys):
    Registry.lie = True
    before = rig_file.read_bytes()
    assert main(["firmware", "pin", "--refresh", "--rig", str(rig_file), *_mirrors(registry)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "nvcr.io" in err[0] and "is not the sha256 of the manifest" in err[0]
    assert rig_file.read_bytes() == before


def test_no_network_is_one_line_naming_the_host(rig_file, capsys):
    with socket.socket() as s:          # a port nothing listens on
        s.bind(("127.0.0.1", 0))
        closed = f"http://127.0.0.1:{s.getsockname()[1]}"
    before = rig_file.read_bytes()
    assert main(["firmware", "pin", "--refresh", "--rig", str(rig_file), *_mirrors(closed)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "nvcr.io: cannot reach it" in err[0] and "left unchanged" in err[0]
    assert rig_file.read_bytes() == before
