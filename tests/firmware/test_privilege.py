"""Least privilege, DDS exposure, verified downloads, unit hardening, the bandwidth budget: each rule of
`firmware check` passes on the default render and fails on the one edit (or rig value) it guards."""
from __future__ import annotations

import re
from pathlib import Path

import pytest
import yaml

from firmware import budget, privilege
from firmware.checks import FAILED, OK, run_checks
from firmware.render import write
from platform_tools.rig import load_rig

SERIALS = ("sensors.thermal.left.serial=93588", "sensors.thermal.right.serial=93599")


@pytest.fixture(scope="module")
def rig():
    return load_rig(None, list(SERIALS))


@pytest.fixture()
def folder(tmp_path, rig) -> Path:
    out = tmp_path / "fw"
    write(rig, out)
    return out


def _edit_compose(folder: Path, fn) -> None:
    doc = yaml.safe_load((folder / "compose.yaml").read_text())
    fn(doc["services"])
    (folder / "compose.yaml").write_text(yaml.safe_dump(doc))


def test_the_default_render_passes_every_rule(folder, rig):
    results = {c.name: c for c in privilege.run(folder, rig)}
    assert {n: c.status for n, c in results.items()} == {n: OK for n in results}, results
    compose = yaml.safe_load((folder / "compose.yaml").read_text())["services"]
    # the ZED X is the only privileged service; the Bosons' drivers run as the rig's user, in video
    assert [n for n, s in compose.items() if s.get("privileged")] == ["zed"]
    assert compose["thermal_left"]["user"] == "1000:1000" and compose["thermal_left"]["group_add"] == ["video"]
    assert compose["thermal_left"]["devices"] == ["/dev/boson_left_video:/dev/boson_left_video"]
    assert compose["health"]["network_mode"] == "none" and "/dev:/dev:ro" not in compose["health"]["volumes"]


@pytest.mark.slow
@pytest.mark.parametrize("edit,message", [
    (lambda s: s["recorder"].update(privileged=True), "recorder is privileged"),
    (lambda s: s["health"].update(pid="host"), "health shares the host pid"),
    (lambda s: s["health"]["volumes"].append("/dev:/dev:ro"), "health mounts /dev"),
    (lambda s: s["thermal_left"]["devices"].append("/dev/boson_right_video:/dev/boson_right_video"),
     "thermal_left devices"),
    (lambda s: s["thermal_right"].pop("user"), "thermal_right runs as root"),
    (lambda s: s["recorder"].pop("cap_drop"), "recorder keeps its capabilities"),
    (lambda s: s["health"].update(security_opt=[]), "health may gain privileges"),
])
def test_a_widened_service_fails_least_privilege(folder, rig, edit, message):
    _edit_compose(folder, edit)
    result = privilege.check_least_privilege(folder, rig)
    assert result.status == FAILED and message in result.detail, result.detail


@pytest.mark.slow
def test_a_zero_domain_id_fails(folder, rig):
    zero = load_rig(None, [*SERIALS, "on_device.ros_domain_id=0"])
    write(zero, folder)
    result = privilege.check_dds(folder, zero)
    assert result.status == FAILED and "ros_domain_id is 0" in result.detail


@pytest.mark.slow
def test_discovery_follows_the_rig_and_the_distribution(tmp_path):
    for sets, env in [((), {"ROS_LOCALHOST_ONLY": "1"}),
                      (("on_device.dds_discovery=subnet",), {"ROS_LOCALHOST_ONLY": "0"}),
                      (("on_device.ros_distro=iron", "on_device.images.zed=rgbt-rig/zed-ros2:iron-l4t-r36",
                        "on_device.images.thermal=rgbt-rig/thermal-ros2:iron-l4t-r36",
                        "on_device.images.tools=rgbt-rig/tools:iron-l4t-r36"),
                       {"ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"})]:
        r = load_rig(None, [*SERIALS, *sets])
        out = tmp_path / "-".join(sets or ("default",)).replace("/", "_")
        write(r, out)
        services = yaml.safe_load((out / "compose.yaml").read_text())["services"]
        for name in ("zed", "thermal_left", "recorder"):
            assert {k: services[name]["environment"][k] for k in env} == env
        assert privilege.check_dds(out, r).status == OK


def test_a_service_outside_the_domain_fails(folder, rig):
    _edit_compose(folder, lambda s: s["recorder"]["environment"].update(ROS_DOMAIN_ID="0"))
    result = privilege.check_dds(folder, rig)
    assert result.status == FAILED and "recorder ROS_DOMAIN_ID=0" in result.detail


def test_sros2_enclaves_put_every_ros_service_in_its_enclave(tmp_path):
    r = load_rig(None, [*SERIALS, "on_device.sros2_enclaves=true"])
    write(r, tmp_path / "fw")
    services = yaml.safe_load((tmp_path / "fw" / "compose.yaml").read_text())["services"]
    for name in ("zed", "thermal_left", "thermal_right", "recorder", "health_topics"):
        env = services[name]["environment"]
        assert env["ROS_SECURITY_STRATEGY"] == "Enforce" and env["ROS_SECURITY_ENCLAVE_OVERRIDE"] == f"/rgbt/{name}"
    assert privilege.check_dds(tmp_path / "fw", r).status == OK


def test_a_download_without_its_checksum_fails(folder, rig):
    path = folder / "docker" / "zed" / "Dockerfile"
    text = path.read_text()
    assert 'sha256sum -c -' in text
    path.write_text(re.sub(r' \\\n && echo "\$\{ZED_SDK_SHA256\}  /tmp/zed_sdk.run" \| sha256sum -c -', "", text))
    result = privilege.check_downloads(folder, rig)
    assert result.status == FAILED and "download.stereolabs.com" in result.detail


def test_unverified_downloads_reads_continued_run_lines():
    verified = 'RUN curl -fsSL https://x/ros.key -o k \\\n && gpg --show-keys --with-colons k | grep fpr'
    assert privilege.unverified_downloads(verified) == []
    assert privilege.unverified_downloads("RUN wget -q https://x/a.run \\\n && sh a.run") == ["https://x/a.run"]
    assert privilege.unverified_downloads("# curl https://x/a.run") == []


def test_the_zed_image_is_built_as_stereolabs_builds_it(folder):
    text = (folder / "docker" / "zed" / "Dockerfile").read_text()
    tegra = text.index("/etc/nv_tegra_release")
    assert tegra < text.index("/tmp/zed_sdk.run -- silent")       # the release file before the installer
    installer = next(ln for ln in text.splitlines() if "/tmp/zed_sdk.run -- silent" in ln)
    assert "skip_drivers" in installer and "skip_cuda" not in installer
    assert "ARG ZED_SDK=5.0" in text and "ARG L4T_VERSION=36.4" in text and "ARG L4T_REVISION=4.4" in text


@pytest.mark.slow
def test_a_pinned_base_image_reaches_the_dockerfiles(tmp_path):
    digest = "sha256:" + "ab" * 32
    r = load_rig(None, [*SERIALS, f"on_device.base_images.ros_digest={digest}"])
    write(r, tmp_path / "fw")
    assert f"ARG BASE_IMAGE=ros:humble-ros-base-jammy@{digest}" in (tmp_path / "fw/docker/tools/Dockerfile").read_text()
    results = {c.name: c.status for c in run_checks(tmp_path / "fw", r)}
    assert results["verified downloads"] == OK and results["dockerfiles"] == OK


@pytest.mark.parametrize("edit,message", [
    (("Wants=zed_x_daemon.service network-online.target", "Wants=zed_x_daemon.service"), "without Wants"),
    (("NoNewPrivileges=yes\n", ""), "NoNewPrivileges=unset"),
])
def test_an_unhardened_unit_fails(folder, edit, message):
    path = folder / "systemd" / "rgbt-rig.service"
    text = path.read_text()
    assert edit[0] in text
    path.write_text(text.replace(*edit))
    result = privilege.check_unit_hardening(folder)
    assert result.status == FAILED and message in result.detail


# ----------------------------------------------------------------------------- what is recorded
def test_the_recording_holds_what_the_dataset_needs(rig):
    from firmware.device.topics import recorded_topics
    topics = recorded_topics(rig)
    for t in ("/zed/zed_node/left/camera_info", "/zed/zed_node/right/camera_info", "/thermal/left/camera_info",
              "/thermal/right/camera_info", "/tf_static", "/diagnostics"):
        assert t in topics
    assert rig.desc.on_device.topics.zed_depth not in topics       # depth off by default
    with_depth = recorded_topics(load_rig(None, ["on_device.zed_depth_mode=NEURAL"]))
    assert rig.desc.on_device.topics.zed_depth in with_depth


def test_the_budget_is_computed_from_the_rig(rig):
    rates = {r.topic: r.bytes_per_s for r in budget.topic_rates(rig)}
    # 640 x (512 + 2 telemetry rows) x 2 bytes x 30 Hz, independently of the module's arithmetic
    assert rates["/thermal/left/image_raw"] == pytest.approx(640 * 514 * 2 * 30 * budget.MCAP_OVERHEAD)
    depth = load_rig(None, ["on_device.zed_depth_mode=NEURAL"])
    d32 = {r.topic: r.bytes_per_s for r in budget.topic_rates(depth)}["/zed/zed_node/depth/depth_registered"]
    assert d32 == pytest.approx(960 * 600 * 4 * 30 * budget.MCAP_OVERHEAD)      # HD1200 / 2, 32FC1
    d16 = load_rig(None, ["on_device.zed_depth_mode=NEURAL", "on_device.zed_depth_openni=true"])
    assert budget.total_mb_per_s(d16) == pytest.approx(budget.total_mb_per_s(depth) - d32 / 2 / 1e6)


@pytest.mark.slow
@pytest.mark.parametrize("sets,status", [
    ((), OK),
    (("on_device.zed_depth_mode=NEURAL",), FAILED),                                     # ~128 MB/s
    (("on_device.zed_depth_mode=NEURAL", "on_device.zed_depth_openni=true"), OK),      # ~93 MB/s
    (("recording.write_budget_mb_per_s=40",), FAILED),
])
def test_an_over_budget_topic_list_fails_the_check(platform_tools, tmp_path, sets, status):
    out = tmp_path / "fw"
    overrides = [a for s in (*SERIALS, *sets) for a in ("--set", s)]
    r = platform_tools("firmware", "render", "--out", str(out), "--no-check", "-q", *overrides)
    assert r.returncode == 0, r.stderr
    import json
    r = platform_tools("firmware", "check", str(out), "--json", *overrides)
    checks = {c["name"]: c for c in json.loads(r.stdout)["checks"]}
    assert checks["bandwidth budget"]["status"] == status, checks["bandwidth budget"]
    assert r.returncode == (0 if status == OK else 1)


def test_a_preset_without_chunk_crcs_fails(rig):
    assert budget.check_chunk_crcs(rig).status == OK
    fast = load_rig(None, ["recording.compression_preset=zstd_fast"])
    assert budget.check_chunk_crcs(fast).status == FAILED
