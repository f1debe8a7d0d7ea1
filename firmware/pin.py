"""Pins of what the image builds download (`platform_tools firmware pin --refresh`): each base image's
digest, asked of its registry, and each pinned archive's sha256, computed from a download; written into
the rig description by a targeted edit of the value only (comments, order and every other line kept).

Registry: the Docker Registry HTTP API v2 as registries speak it (Docker Hub, nvcr.io): HEAD
``/v2/<repo>/manifests/<tag>``; on 401 the ``WWW-Authenticate: Bearer realm=...,service=...,scope=...``
challenge names the token endpoint; its JSON ``token`` (or ``access_token``) goes back as
``Authorization: Bearer``. The digest is the ``Docker-Content-Digest`` header of the manifest (the
multi-arch index when there is one: docker picks the Orin's arm64 image from it), checked against the
sha256 of the manifest's bytes (GET).

`mirrors` maps a host to another base URL (a registry mirror, or a local server in tests).
"""
from __future__ import annotations

import hashlib
import json
import re
import urllib.error
import urllib.parse
import urllib.request
from dataclasses import dataclass
from typing import Callable, Mapping

import yaml

from firmware.context import images_context
from platform_tools.rig import Rig

#: Docker Hub's registry host for images named without one (``ros:humble-...`` is library/ros)
DOCKER_HUB = "registry-1.docker.io"
#: manifest media types asked for, the multi-arch index first
MANIFEST_TYPES = ("application/vnd.oci.image.index.v1+json",
                  "application/vnd.docker.distribution.manifest.list.v2+json",
                  "application/vnd.oci.image.manifest.v1+json",
                  "application/vnd.docker.distribution.manifest.v2+json")
TIMEOUT_S = 30
_CHUNK = 1 << 20


class PinError(Exception):
    """A pin cannot be refreshed: the message is one line naming the host, image or key."""


@dataclass(frozen=True)
class ImageRef:
    host: str
    repo: str
    tag: str

    @classmethod
    def parse(cls, ref: str) -> "ImageRef":
        """nvcr.io/nvidia/l4t-jetpack:r36.4.0, ros:humble-ros-base-jammy (Docker Hub: library/ros)."""
        ref = ref.split("@", 1)[0]
        name, _, tag = ref.rpartition(":") if ":" in ref.rsplit("/", 1)[-1] else (ref, "", "latest")
        first, _, rest = name.partition("/")
        if rest and ("." in first or ":" in first or first == "localhost"):
            return cls(first, rest, tag)
        return cls(DOCKER_HUB, name if "/" in name else f"library/{name}", tag)


def _base(host: str, mirrors: Mapping[str, str]) -> str:
    return mirrors.get(host, f"https://{host}").rstrip("/")


def _open(req: urllib.request.Request, host: str):
    try:
        return urllib.request.urlopen(req, timeout=TIMEOUT_S)
    except urllib.error.HTTPError:
        raise
    except (urllib.error.URLError, OSError) as exc:
        reason = getattr(exc, "reason", exc)
        raise PinError(f"{host}: cannot reach it ({reason}); pinning needs the network") from None


def _challenge(header: str) -> dict[str, str]:
    if not header.lower().startswith("bearer "):
        raise PinError(f"unsupported registry authentication {header.split(' ')[0]!r}")
    return dict(re.findall(r'(\w+)="([^"]*)"', header))


def _token(challenge: dict[str, str], host: str) -> str:
    realm = challenge.get("realm")
    if not realm:
        raise PinError(f"{host}: the registry's Bearer challenge names no realm")
    query = urllib.parse.urlencode({k: v for k, v in challenge.items() if k in ("service", "scope")})
    with _open(urllib.request.Request(f"{realm}?{query}" if query else realm), urllib.parse.urlsplit(realm).netloc) as r:
        doc = json.loads(r.read())
    token = doc.get("token") or doc.get("access_token")
    if not token:
        raise PinError(f"{host}: the token endpoint {realm} answered without a token")
    return token


def image_digest(ref: str, mirrors: Mapping[str, str] | None = None) -> str:
    """``sha256:...`` of the image's manifest on its registry, the header checked against the bytes."""
    image = ImageRef.parse(ref)
    url = f"{_base(image.host, mirrors or {})}/v2/{image.repo}/manifests/{image.tag}"
    headers = {"Accept": ", ".join(MANIFEST_TYPES)}

    def fetch(method: str):
        return _open(urllib.request.Request(url, headers=headers, method=method), image.host)

    try:
        try:
            r = fetch("GET")
        except urllib.error.HTTPError as exc:
            if exc.code != 401:
                raise
            headers["Authorization"] = f"Bearer {_token(_challenge(exc.headers.get('WWW-Authenticate', '')), image.host)}"
            r = fetch("GET")
        with r:
            body = r.read()
            said = r.headers.get("Docker-Content-Digest")
    except urllib.error.HTTPError as exc:
        raise PinError(f"{image.host}: {ref}: manifest {exc.code} {exc.reason}") from None
    got = "sha256:" + hashlib.sha256(body).hexdigest()
    if said and said != got:
        raise PinError(f"{image.host}: {ref}: Docker-Content-Digest {said} is not the sha256 of the manifest ({got})")
    return got


def archive_sha256(url: str, mirrors: Mapping[str, str] | None = None,
                   progress: Callable[[int], None] | None = None) -> str:
    """sha256 of a download, streamed (the ZED SDK installer is over a gigabyte)."""
    parts = urllib.parse.urlsplit(url)
    mirrors = mirrors or {}
    if parts.netloc in mirrors:
        url = _base(parts.netloc, mirrors) + parts.path + (f"?{parts.query}" if parts.query else "")
    h = hashlib.sha256()
    try:
        with _open(urllib.request.Request(url), parts.netloc) as r:
            while block := r.read(_CHUNK):
                h.update(block)
                if progress:
                    progress(len(block))
    except urllib.error.HTTPError as exc:
        raise PinError(f"{parts.netloc}: {url}: {exc.code} {exc.reason}") from None
    return h.hexdigest()


@dataclass(frozen=True)
class Pin:
    key: tuple[str, ...]     # where the rig description keeps it
    kind: str                # "image" (a registry digest) or "archive" (a download's sha256)
    source: str              # the image reference or the URL
    current: str | None

    def to_dict(self) -> dict:
        return {"key": ".".join(self.key), "kind": self.kind, "source": self.source, "current": self.current}


def pins(rig: Rig) -> list[Pin]:
    """What the rendered Dockerfiles pull or download, each with the rig key that pins it."""
    od = rig.desc.on_device
    images = images_context(rig)
    return [Pin(("on_device", "base_images", "l4t_jetpack_digest"), "image", images["base"],
                od.base_images.l4t_jetpack_digest),
            Pin(("on_device", "base_images", "ros_digest"), "image", images["ros_base"], od.base_images.ros_digest),
            Pin(("on_device", "downloads", "zed_sdk_sha256"), "archive", images["zed_sdk_url"],
                od.downloads.zed_sdk_sha256)]


def fetch(pin: Pin, mirrors: Mapping[str, str] | None = None) -> str:
    """The pin's value as its source gives it now (the network)."""
    if pin.kind == "image":
        return image_digest(pin.source, mirrors)
    return archive_sha256(pin.source, mirrors)


# ----------------------------------------------------------------------------- the targeted edit
def _value_node(root: yaml.Node, path: tuple[str, ...]) -> yaml.ScalarNode:
    node = root
    for key in path:
        if not isinstance(node, yaml.MappingNode):
            raise PinError(f"{'.'.join(path)}: not a mapping at {key}")
        for k, v in node.value:
            if isinstance(k, yaml.ScalarNode) and k.value == key:
                node = v
                break
        else:
            raise PinError(f"{'.'.join(path)}: no such key in the rig description")
    if not isinstance(node, yaml.ScalarNode):
        raise PinError(f"{'.'.join(path)}: not a single value")
    return node


def set_values(text: str, values: Mapping[tuple[str, ...], str]) -> str:
    """`text` with the scalar at each key path replaced by a quoted value; nothing else changes (the
    YAML's own marks give each value's span, so comments and layout stay)."""
    root = yaml.compose(text, Loader=yaml.SafeLoader)
    spans = []
    for path, value in values.items():
        node = _value_node(root, path)
        spans.append((node.start_mark.index, node.end_mark.index, json.dumps(value)))
    for start, end, new in sorted(spans, reverse=True):
        text = text[:start] + new + text[end:]
    return text
