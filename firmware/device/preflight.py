"""Pre-flight checks before a recording, and `rig-device doctor` (`platform_tools doctor`).

1. data drive   the output folder is on the filesystem mounted at recording.data_mount, and that
                is not the root filesystem (the Orin's eMMC)
2. free space   at least recording.min_free_gb free there
3. cameras      each Boson's video node (/dev/<device_name>_video, from the udev rules) and its
                serial port, answering with the serial number the rig description expects
4. trigger      each Boson's ISP frame counter advances at sync.rate_hz (the capture card's trigger)
5. sync mode    each Boson's external sync mode is sync.boson_mode
6. telemetry    each Boson's telemetry rows are on when on_device.thermal_telemetry_rows > 0
7. gpio pinmux  the button and LED pins are GPIOs (hostchecks; skipped without root and debugfs)
8. host clock   the host clock is synchronised: chrony leap status, stratum, offset (hostchecks)

Camera checks go through the Boson tooling (platform_tools.boson); with ``boson=False`` they are
reported as skipped, never as passed.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

from firmware.device import bosonprobe, hostchecks
from firmware.device.storage import GB, free_bytes, mount_point
from platform_tools.rig import Rig
from platform_tools.rig.checks import FAILED, OK, SKIPPED, Check


@dataclass
class Report:
    checks: list[Check] = field(default_factory=list)
    cameras: dict[str, dict] = field(default_factory=dict)   # side -> serial, firmware, port

    @property
    def ok(self) -> bool:
        return all(c.status != FAILED for c in self.checks)

    def failed(self) -> list[Check]:
        return [c for c in self.checks if c.status == FAILED]

    def to_dict(self) -> dict:
        return {"ok": self.ok, "checks": [c.to_dict() for c in self.checks], "cameras": self.cameras}


def check_data_drive(rig: Rig, output_dir: Path) -> Check:
    want = Path(rig.desc.recording.data_mount)
    got = mount_point(output_dir)
    if not os.path.ismount(want):
        return Check("data drive", FAILED, f"{want} (recording.data_mount) is not a mount point: mount the data "
                                           f"drive there; recordings would go to {got}")
    if got != want:
        return Check("data drive", FAILED, f"{output_dir} is on {got}, not on the data drive {want}")
    if os.stat(want).st_dev == os.stat("/").st_dev:
        return Check("data drive", FAILED, f"{want} is on the root filesystem (the eMMC), not a separate drive")
    return Check("data drive", OK, f"{output_dir} is on {want}")


def check_free_space(rig: Rig, output_dir: Path) -> Check:
    need = rig.desc.recording.min_free_gb
    free = free_bytes(output_dir) / GB
    status = OK if free >= need else FAILED
    return Check("free space", status, f"{free:.1f} GB free on {mount_point(output_dir)}, need {need:g} GB "
                                       f"(recording.min_free_gb)")


def check_video_nodes(rig: Rig, dev_dir: Path) -> Check:
    missing = []
    for side in ("left", "right"):
        node = dev_dir / rig.boson_device_nodes(side)["video"]
        if not node.exists():
            missing.append(f"{side} {node}")
    if missing:
        return Check("thermal video", FAILED, f"missing: {', '.join(missing)} (camera unplugged, or the udev rules "
                                              f"not installed: firmware/udev)")
    return Check("thermal video", OK, "both video nodes present")


def run_preflight(rig: Rig, output_dir: Path | None = None, *, boson: bool = True,
                  dev_dir: Path = Path("/dev"), root: Path = Path("/")) -> Report:
    output_dir = Path(output_dir or rig.desc.recording.output_dir)
    report = Report()
    report.checks += [check_data_drive(rig, output_dir), check_free_space(rig, output_dir),
                      check_video_nodes(rig, dev_dir), *hostchecks.run(rig, root)]
    if boson:
        report.checks += bosonprobe.checks(rig, dev_dir, report.cameras)
    else:
        report.checks += [Check(n, SKIPPED, "--no-boson")
                          for n in ("thermal cameras", "trigger", "sync mode", "telemetry")]
    return report
