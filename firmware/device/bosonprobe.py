"""The Boson part of the pre-flight, through the Boson tooling (platform_tools.boson): each camera
answers on its serial port with the expected serial number, its frame counter advances at the
trigger rate, its external sync mode is the configured one, and its telemetry rows (where the FFC
status is read from) are on when the rig records them."""
from __future__ import annotations

import time
from pathlib import Path

from platform_tools.boson import commands as C
from platform_tools.boson import discovery
from platform_tools.boson.client import BosonClient
from platform_tools.boson.codes import BosonError
from platform_tools.boson.transport import SerialTransport
from platform_tools.rig import Rig
from firmware.device.preflight import FAILED, OK, SKIPPED, SYNC_NAMES, TRIGGER_TOLERANCE, Check


def _port(rig: Rig, side: str, dev_dir: Path, found) -> tuple[str, int | None]:
    """The udev name when it exists (on the Orin, in the container), else the by-id discovery."""
    cam = getattr(rig.desc.sensors.thermal, side)
    udev = dev_dir / f"{cam.device_name}_serial"
    if udev.exists():
        return str(udev), cam.serial
    target = discovery.select_targets(side, rig, found)[0]
    return target.port, target.serial


def _probe(rig: Rig, side: str, port: str, serial: int | None, window_s: float) -> dict:
    client = BosonClient(SerialTransport(port), label=side)
    with client.open():
        sn = client.call(C.GET_CAMERA_SN)
        if serial is not None and sn != serial:
            raise discovery.SelectionError(f"{port} answers with SN {sn}, the rig expects {serial} "
                                           f"(sensors.thermal.{side}.serial)")
        rev = client.call(C.GET_SOFTWARE_REV)
        mode = C.enum_name(client.call(C.GET_EXT_SYNC))
        telemetry = C.enum_name(client.call(C.GET_TELEMETRY))
        c0, t0 = client.call(C.GET_FRAME_COUNT), time.monotonic()
        time.sleep(window_s)
        c1, t1 = client.call(C.GET_FRAME_COUNT), time.monotonic()
    return {"serial": sn, "firmware": ".".join(map(str, rev)) if isinstance(rev, (tuple, list)) else str(rev),
            "port": port, "sync_mode": str(mode), "telemetry": str(telemetry), "frame_rate_hz": round(((c1 - c0) & 0xFFFFFFFF) / (t1 - t0), 2)}


def checks(rig: Rig, dev_dir: Path, cameras: dict) -> list[Check]:
    found = discovery.discover()
    problems, sync_bad, trig_bad, telemetry_bad = [], [], [], []
    want_telemetry = rig.desc.on_device.thermal_telemetry_rows > 0
    rate = rig.desc.sync.rate_hz
    want_mode = SYNC_NAMES[rig.desc.sync.boson_mode]
    for side in ("left", "right"):
        try:
            port, serial = _port(rig, side, dev_dir, found)
            info = _probe(rig, side, port, serial, rig.desc.on_device.trigger_watch_s)
        except (discovery.SelectionError, BosonError, OSError) as exc:
            problems.append(f"{side}: {exc}")
            continue
        except Exception as exc:  # noqa: BLE001  a camera that does not answer is a failed check, not a crash
            problems.append(f"{side}: {type(exc).__name__}: {exc}")
            continue
        cameras[side] = info
        if not info["sync_mode"].upper().endswith(want_mode):
            sync_bad.append(f"{side} is {info['sync_mode']}")
        if want_telemetry and info["telemetry"] != "enabled":
            telemetry_bad.append(f"{side} is {info['telemetry']}")
        if abs(info["frame_rate_hz"] - rate) > TRIGGER_TOLERANCE * rate:
            trig_bad.append(f"{side} at {info['frame_rate_hz']:.1f} Hz")
    out = [Check("thermal cameras", FAILED if problems else OK,
                 "; ".join(problems) if problems else
                 ", ".join(f"{s} SN {c['serial']} fw {c['firmware']}" for s, c in cameras.items()))]
    if not cameras:
        return out + [Check(n, SKIPPED, "no camera answered") for n in ("trigger", "sync mode", "telemetry")]
    out.append(Check("trigger", FAILED if trig_bad else OK,
                     (f"frame counters: {', '.join(trig_bad)}, expected {rate:g} Hz (sync.rate_hz): is the "
                      f"{rig.desc.sync.source_part} trigger running and wired?") if trig_bad else
                     f"frame counters advance at {rate:g} Hz"))
    out.append(Check("sync mode", FAILED if sync_bad else OK,
                     f"{', '.join(sync_bad)}, expected {want_mode} (sync.boson_mode): run "
                     f"`platform_tools boson-config`" if sync_bad else f"{want_mode} as configured"))
    if want_telemetry:
        out.append(Check("telemetry", FAILED if telemetry_bad else OK,
                         f"{', '.join(telemetry_bad)}: the recording would carry no FFC status "
                         f"(on_device.thermal_telemetry_rows); run `platform_tools boson-config`" if telemetry_bad
                         else "on: the FFC status is recorded from the telemetry rows"))
    else:
        out.append(Check("telemetry", SKIPPED, "on_device.thermal_telemetry_rows is 0"))
    return out
