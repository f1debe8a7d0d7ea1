"""`rig-device doctor --bring-up`: one check per assumption this project could only assume, measured on the
device where it can be, "not measurable here: ..." (skipped, never passed) where it cannot.

usb serial        each Boson's USB serial string (its by-id name) is the serial number it answers over FSLP
telemetry layout  a frame dump's telemetry rows decode (counter, FFC state bits 4-5 of the status word at
                  byte 76) to plausible values (``--frames DIR`` with ``<side>.raw``: one Y16 frame, rows
                  included, e.g. ``v4l2-ctl -d /dev/boson_left_video --stream-mmap --stream-count=1
                  --stream-to=left.raw``)
trigger rate      the Bosons' frame counters advance at sync.rate_hz (the pre-flight's measurement)
trigger edge      which edge the Bosons see: not measurable from this device alone (a scope on J17, or the
                  ZED-thermal stamp offset of a recording: 8.33 ms at 30 Hz if the other edge)
zed sdk / l4t     /etc/nv_tegra_release is the L4T the images are built for; the ZED SDK version when the
                  host has /usr/local/zed (it is in the zed image otherwise: not measurable here)
gpio pinmux       (every pre-flight's: hostchecks) the button and LED pins are GPIOs in the pinmux table
recorded rate     the newest recording's bytes per second against the budget computed from the rig and
                  recording.write_budget_mb_per_s
host clock        (every pre-flight's: hostchecks) chrony synchronised, stratum, offset
"""
from __future__ import annotations

import re
from datetime import datetime
from pathlib import Path

import numpy as np

from firmware import budget
from firmware.context import L4T_RELEASES, ZED_SDK
from firmware.device import metadata
from platform_tools.boson import discovery
from platform_tools.boson.discovery import Target
from platform_tools.boson.operations import open_client, read_info
from platform_tools.boson.telemetry import TelemetryError, decode_frame
from platform_tools.rig import Rig
from platform_tools.rig.checks import FAILED, OK, SKIPPED, Check
# the GPIO pinmux and the host clock are every pre-flight's (hostchecks), in the bring-up report with it
from firmware.device.hostchecks import NOT_HERE, check_host_clock, check_pinmux  # noqa: F401
#: how far (a fraction) the measured recorded rate may exceed the computed one
RATE_TOLERANCE = 0.25


def check_usb_serial() -> Check:
    found = [f for f in discovery.discover() if f.source == "by-id"]
    if not found:
        return Check("usb serial", SKIPPED, NOT_HERE + "no Boson serial port under /dev/serial/by-id")
    bad, good = [], []
    for f in found:
        try:
            with open_client(Target(f.port, f.port, None)) as client:
                sn = read_info(client, ("serial",))["serial"]
        except Exception as exc:  # noqa: BLE001  a camera that does not answer is a failed check
            bad.append(f"{f.port}: {type(exc).__name__}: {exc}")
            continue
        (good if f.serial == sn else bad).append(f"{Path(f.port).name} answers SN {sn}" +
                                                ("" if f.serial == sn else f", its USB serial string is {f.serial}"))
    return Check("usb serial", FAILED if bad else OK, "; ".join(bad or good))


def check_telemetry(rig: Rig, frames_dir: Path | None) -> Check:
    rows = rig.desc.on_device.thermal_telemetry_rows
    model = rig.camera_model(rig.desc.sensors.thermal.camera_model)
    if rows == 0:
        return Check("telemetry layout", SKIPPED, "on_device.thermal_telemetry_rows is 0")
    files = {s: frames_dir / f"{s}.raw" for s in ("left", "right")} if frames_dir else {}
    files = {s: f for s, f in files.items() if f.is_file()}
    if not files:
        return Check("telemetry layout", SKIPPED, NOT_HERE + "no frame dump (--frames DIR with left.raw, right.raw)")
    shape = (model.height_px + rows, model.width_px)
    bad, good = [], []
    for side, f in files.items():
        data = np.frombuffer(f.read_bytes(), dtype="<u2")
        if data.size != shape[0] * shape[1]:
            bad.append(f"{f}: {data.size * 2} bytes, expected {shape[1]}x{shape[0]} Y16")
            continue
        try:
            t = decode_frame(data.reshape(shape), rows)
        except TelemetryError as exc:
            bad.append(f"{side}: {exc}")
            continue
        if t.frame_counter == 0 or t.ffc_frame > t.frame_counter or t.ffc_status not in (0, 1, 2, 3):
            bad.append(f"{side}: counter {t.frame_counter}, FFC frame {t.ffc_frame}, FFC state {t.ffc_status}: "
                       f"not a plausible telemetry row (byte layout or FFC bits differ)")
        else:
            good.append(f"{side}: counter {t.frame_counter}, FFC frame {t.ffc_frame}, FFC state {t.ffc_status}")
    return Check("telemetry layout", FAILED if bad else OK, "; ".join(bad or good))


def check_trigger_rate(rig: Rig, cameras: dict) -> Check:
    rate = rig.desc.sync.rate_hz
    if not cameras:
        return Check("trigger rate", SKIPPED, NOT_HERE + "no Boson answered")
    got = {s: c["frame_rate_hz"] for s, c in cameras.items()}
    off = [f"{s} at {r:g} Hz" for s, r in got.items() if abs(r - rate) > 0.2 * rate]
    return Check("trigger rate", FAILED if off else OK,
                 f"{', '.join(off) if off else ', '.join(f'{s} {r:g} Hz' for s, r in got.items())}, "
                 f"expected {rate:g} Hz (sync.rate_hz)")


def check_trigger_edge() -> Check:
    return Check("trigger edge", SKIPPED, NOT_HERE + "needs a scope on the capture card's J17, or the ZED-thermal "
                                         "stamp offset of a recording (a quarter period if the other edge)")


def check_zed_l4t(rig: Rig, root: Path) -> Check:
    f = root / "etc" / "nv_tegra_release"
    if not f.is_file():
        return Check("zed sdk / l4t", SKIPPED, NOT_HERE + f"no {f}: not a Jetson")
    m = re.search(r"#\s*R(\d+)\s*\(release\),\s*REVISION:\s*([\d.]+)", f.read_text())
    if m is None:
        return Check("zed sdk / l4t", FAILED, f"{f}: no '# Rnn (release), REVISION: x.y' line")
    release = f"r{m.group(1)}"
    want = L4T_RELEASES.get(release)
    got = f"R{m.group(1)}.{m.group(2)}"
    if want is None or m.group(2) != want["l4t_revision"]:
        known = ", ".join(f"R{k[1:]}.{v['l4t_revision']}" for k, v in L4T_RELEASES.items())
        return Check("zed sdk / l4t", FAILED, f"L4T {got}; the images are built for {known} (ZED SDK {ZED_SDK})")
    hpp = root / "usr" / "local" / "zed" / "include" / "sl" / "Camera.hpp"
    sdk = NOT_HERE + "no ZED SDK on the host (it is in the zed image)"
    if hpp.is_file():
        v = dict(re.findall(r"#define\s+ZED_SDK_(MAJOR|MINOR|PATCH)_VERSION\s+(\d+)", hpp.read_text()))
        sdk = f"ZED SDK {v.get('MAJOR', '?')}.{v.get('MINOR', '?')}.{v.get('PATCH', '?')}"
        if f"{v.get('MAJOR')}.{v.get('MINOR')}" != ZED_SDK:
            return Check("zed sdk / l4t", FAILED, f"L4T {got} with {sdk}; the images pair it with ZED SDK {ZED_SDK}")
    return Check("zed sdk / l4t", OK, f"L4T {got} (images: ZED SDK {ZED_SDK}); host: {sdk}")


def check_recorded_rate(rig: Rig, output_dir: Path) -> Check:
    metas = sorted(output_dir.glob(f"*/{metadata.FILE_NAME}")) if output_dir.is_dir() else []
    done = [m for m in metas if (metadata.read(m.parent).get("duration_s") or 0) > 0]
    if not done:
        return Check("recorded rate", SKIPPED, NOT_HERE + f"no finished recording in {output_dir}: record one first")
    folder = done[-1].parent
    duration = float(metadata.read(folder)["duration_s"])
    size = sum(f.stat().st_size for f in (folder / "bag").glob("*.mcap"))
    got = size / duration / budget.MB
    want, limit = budget.total_mb_per_s(rig), rig.desc.recording.write_budget_mb_per_s
    detail = (f"{folder.name}: {got:.1f} MB/s over {duration:g} s; computed {want:.1f} MB/s (before compression), "
              f"budget {limit:g} MB/s (recording.write_budget_mb_per_s)")
    return Check("recorded rate", FAILED if got > limit or got > want * (1 + RATE_TOLERANCE) else OK, detail)


def run(rig: Rig, cameras: dict, *, root: Path, output_dir: Path, frames_dir: Path | None,
        boson: bool = True) -> list[Check]:
    skipped = [Check("usb serial", SKIPPED, "--no-boson")]
    return [*(([check_usb_serial()]) if boson else skipped), check_telemetry(rig, frames_dir),
            check_trigger_rate(rig, cameras), check_trigger_edge(), check_zed_l4t(rig, root),
            check_recorded_rate(rig, output_dir)]


def report_markdown(rig: Rig, checks: list[Check], cameras: dict) -> str:
    lines = [f"# Bring-up report: rig {rig.desc.name}", "",
             f"Rig hash `{rig.hash[:12]}`, {datetime.now().astimezone().isoformat(timespec='seconds')}.", "",
             "| check | status | detail |", "|---|---|---|"]
    lines += [f"| {c.name} | {c.status} | {c.detail.replace('|', '/')} |" for c in checks]
    lines += ["", "Cameras: " + (", ".join(f"{s} SN {c.get('serial')} fw {c.get('firmware')}"
                                           for s, c in cameras.items()) or "none answered"), ""]
    return "\n".join(lines)
