"""The Boson part of the pre-flight, through the Boson tooling (platform_tools.boson): each camera
answers on its serial port with the expected serial number, its frame counter advances at the
trigger rate, its external sync mode is the configured one, and its telemetry rows (where the FFC
status is read from) are on when the rig records them, at the location the FFC decoder reads them from
(platform_tools.boson.telemetry.EXPECTED_LOCATION): rows at the top while the decoder reads the bottom
give every frame of a recording a wrong FFC status."""
from __future__ import annotations

from pathlib import Path

from platform_tools.boson import discovery
from platform_tools.boson.codes import BosonError
from platform_tools.boson.discovery import Target
from platform_tools.boson.operations import measure_frame_rate, open_client, read_info
from platform_tools.boson.syncsetup import SYNC_MODES
from platform_tools.boson.telemetry import EXPECTED_LOCATION
from platform_tools.rig import Rig
from platform_tools.rig.checks import FAILED, OK, SKIPPED, Check

#: how far (a fraction of sync.rate_hz) a camera's measured frame rate may be from the trigger's
TRIGGER_TOLERANCE = 0.2
#: what the pre-flight reads of each camera (platform_tools.boson.operations.INFO)
PROBE_KEYS = ("serial", "firmware", "sync_mode", "telemetry", "telemetry_location")


def _target(rig: Rig, side: str, dev_dir: Path, found: list[discovery.Found]) -> Target:
    """The udev name when it exists (on the Orin, in the container), else the by-id discovery."""
    udev = dev_dir / rig.boson_device_nodes(side)["serial"]
    if udev.exists():
        return Target(side, str(udev), getattr(rig.desc.sensors.thermal, side).serial)
    return discovery.select_targets(side, rig, found)[0]


def probe(target: Target, window_s: float) -> dict:
    """serial, firmware, port, sync_mode, telemetry and frame_rate_hz (over ``window_s`` s) of one
    camera; raises SelectionError when it answers with another serial number than the rig's."""
    with open_client(target) as client:
        info = read_info(client, PROBE_KEYS)
        if target.serial is not None and info["serial"] != target.serial:
            raise discovery.SelectionError(f"{target.port} answers with SN {info['serial']}, the rig expects "
                                           f"{target.serial} (sensors.thermal.{target.label}.serial)")
        rate = measure_frame_rate(client, window_s)
    return {"serial": info["serial"], "firmware": info["firmware"], "port": target.port,
            "sync_mode": str(info["sync_mode"]), "telemetry": str(info["telemetry"]),
            "telemetry_location": str(info["telemetry_location"]),
            "frame_rate_hz": round(rate, 2)}


def checks(rig: Rig, dev_dir: Path, cameras: dict) -> list[Check]:
    """The thermal cameras, trigger, sync mode and telemetry checks; fills ``cameras`` (side -> probe)."""
    found = discovery.discover()
    problems, sync_bad, trig_bad, telemetry_bad = [], [], [], []
    want_telemetry = rig.desc.on_device.thermal_telemetry_rows > 0
    rate = rig.desc.sync.rate_hz
    want_mode = SYNC_MODES[rig.desc.sync.boson_mode].name
    for side in ("left", "right"):
        try:
            info = probe(_target(rig, side, dev_dir, found), rig.desc.on_device.trigger_watch_s)
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
        elif want_telemetry and info["telemetry_location"] != EXPECTED_LOCATION:
            telemetry_bad.append(f"{side} has its rows at the {info['telemetry_location']}, the FFC decoder reads "
                                 f"the {EXPECTED_LOCATION}")
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
                         f"{', '.join(telemetry_bad)}: the recording would carry no FFC status or a wrong one "
                         f"(on_device.thermal_telemetry_rows); run `platform_tools boson-config`" if telemetry_bad
                         else f"on, rows at the {EXPECTED_LOCATION}: the FFC status is recorded from them"))
    else:
        out.append(Check("telemetry", SKIPPED, "on_device.thermal_telemetry_rows is 0"))
    return out
