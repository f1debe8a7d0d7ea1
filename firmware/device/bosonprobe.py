"""The Boson part of the pre-flight, through the Boson tooling (platform_tools.boson).

Which camera is which is asked of the cameras (platform_tools.boson.identity): every serial port that may
hold a Boson (the by-id links, the port list, and the rig's udev names ``/dev/<device_name>_serial``) is
asked its serial number over the serial link, and left / right are mapped by that answer, not by the udev
name (the udev rules match the USB serial string, which this project could not check equals the camera's
serial). The "thermal cameras" check fails on a rig serial not set, a rig camera no port answers as
(missing), one serial on two ports (duplicate), a rig camera on a port whose USB string names another
camera (swapped), and a udev name that leads to another camera than its side's; it says which port and
which physical USB port (by-path) holds each camera, and names any camera the rig does not know.

Then, on each identified camera at once: its frame counter advances at the trigger rate, its external
sync mode is the configured one, and its telemetry rows (where the FFC status is read from) are on when
the rig records them, at the location the FFC decoder reads them from
(platform_tools.boson.telemetry.EXPECTED_LOCATION): rows at the top while the decoder reads the bottom
give every frame of a recording a wrong FFC status."""
from __future__ import annotations

from pathlib import Path

from platform_tools.boson import discovery, identity
from platform_tools.boson.client import BosonClient
from platform_tools.boson.codes import BosonError
from platform_tools.boson.discovery import Found, Target
from platform_tools.boson.operations import ClientPool, measure_frame_rate, per_camera, read_info
from platform_tools.boson.options import config_command
from platform_tools.boson.syncsetup import SYNC_MODES
from platform_tools.boson.telemetry import EXPECTED_LOCATION
from platform_tools.rig import Rig
from platform_tools.rig.checks import FAILED, OK, SKIPPED, Check

#: how far (a fraction of sync.rate_hz) a camera's measured frame rate may be from the trigger's
TRIGGER_TOLERANCE = 0.2
#: what the pre-flight reads of each camera (platform_tools.boson.operations.INFO)
PROBE_KEYS = ("serial", "firmware", "sync_mode", "telemetry", "telemetry_location")
SIDES = ("left", "right")


def candidate_ports(rig: Rig, dev_dir: Path, found: list[Found]) -> tuple[list[Found], dict[str, str]]:
    """Every serial port that may hold a Boson, one per device: what discovery found, and the rig's udev
    names that lead to a device discovery did not see (discovery.udev_ports); and side -> the device its
    udev name leads to (only the names that exist)."""
    extra, udev = discovery.udev_ports(rig, dev_dir, found)
    return [f for f in found if f.source != "usb"] + extra, udev


def _udev_problems(rig: Rig, udev: dict[str, str], known: identity.RigSurvey,
                   identified: list[identity.Identified]) -> list[str]:
    """A udev name that leads to another camera than its side's (the rules match the USB string)."""
    answered = {i.found.device: i for i in identified}
    out = []
    for side, device in udev.items():
        name = rig.boson_device_nodes(side)["serial"]
        mine = known.cameras.get(side)
        if mine is not None and mine.found.device == device:
            continue
        there = answered.get(device)
        said = (f"the camera answering SN {there.serial}" if there is not None and there.serial is not None
                else "a port that does not answer")
        out.append(f"udev name {name} leads to {said}, not to the {side} camera "
                   f"(sensors.thermal.{side}.serial): the udev rules match the USB serial string")
    return out


def probe(client: BosonClient, found: Found, window_s: float) -> dict:
    """serial, firmware, port, by_path, sync_mode, telemetry, telemetry_location and frame_rate_hz (over
    ``window_s`` s) of one identified camera (its serial is the one identity read: not asked again)."""
    info = read_info(client, PROBE_KEYS)
    rate = measure_frame_rate(client, window_s)
    return {"serial": info["serial"], "firmware": info["firmware"], "port": found.port, "by_path": found.by_path,
            "sync_mode": str(info["sync_mode"]), "telemetry": str(info["telemetry"]),
            "telemetry_location": str(info["telemetry_location"]), "frame_rate_hz": round(rate, 2)}


def _identity_check(known: identity.RigSurvey, problems: list[str], cameras: dict) -> Check:
    where = ", ".join(f"{s} SN {c['serial']} fw {c['firmware']} on {known.cameras[s].found.where()}"
                      for s, c in cameras.items())
    notes = "".join(f"; note: {n}" for n in known.notes)
    if problems:
        return Check("thermal cameras", FAILED, "; ".join(problems) + (f"; {where}" if where else "") + notes)
    return Check("thermal cameras", OK, where + " (identified by the serial each answers)" + notes)


def checks(rig: Rig, dev_dir: Path, cameras: dict) -> list[Check]:
    """The thermal cameras (identity), trigger, sync mode and telemetry checks; fills ``cameras`` (side ->
    probe)."""
    ports, udev = candidate_ports(rig, dev_dir, discovery.discover())
    with ClientPool() as pool:
        identified = identity.identify(ports, pool.open, per_camera)
        known = identity.survey(rig, identified, ports)
        problems = known.problems + _udev_problems(rig, udev, known, identified)
        sides = [s for s in SIDES if s in known.cameras]

        def one(side: str):
            i = known.cameras[side]
            try:
                return probe(pool.open(Target(side, i.found.port, i.serial, i.found.video)), i.found,
                             rig.desc.on_device.trigger_watch_s)
            except (BosonError, OSError) as exc:
                return f"{side}: {exc}"
            except Exception as exc:  # noqa: BLE001  a camera that misbehaves is a failed check, not a crash
                return f"{side}: {type(exc).__name__}: {exc}"
        for side, info in zip(sides, per_camera(sides, one)):
            if isinstance(info, str):
                problems.append(info)
            else:
                cameras[side] = info
    out = [_identity_check(known, problems, cameras)]
    if not cameras:
        return out + [Check(n, SKIPPED, "no camera answered") for n in ("trigger", "sync mode", "telemetry")]
    return out + _state_checks(rig, cameras, dev_dir)


def _fix_command(rig: Rig, dev_dir: Path) -> str:
    """The device's command (the images install no platform_tools) that puts both cameras as the rig wants
    them: its sync mode and telemetry rows, on the rig file and overrides this pre-flight checked."""
    return f"`{config_command('rig-device', rig, dev_dir)}`"


def _state_checks(rig: Rig, cameras: dict, dev_dir: Path) -> list[Check]:
    sync_bad, trig_bad, telemetry_bad = [], [], []
    want_telemetry = rig.desc.on_device.thermal_telemetry_rows > 0
    rate = rig.desc.sync.rate_hz
    want_mode = SYNC_MODES[rig.desc.sync.boson_mode].name
    for side, info in cameras.items():
        if not info["sync_mode"].upper().endswith(want_mode):
            sync_bad.append(f"{side} is {info['sync_mode']}")
        if want_telemetry and info["telemetry"] != "enabled":
            telemetry_bad.append(f"{side} is {info['telemetry']}")
        elif want_telemetry and info["telemetry_location"] != EXPECTED_LOCATION:
            telemetry_bad.append(f"{side} has its rows at the {info['telemetry_location']}, the FFC decoder reads "
                                 f"the {EXPECTED_LOCATION}")
        if abs(info["frame_rate_hz"] - rate) > TRIGGER_TOLERANCE * rate:
            trig_bad.append(f"{side} at {info['frame_rate_hz']:.1f} Hz")
    out = [Check("trigger", FAILED if trig_bad else OK,
                 (f"frame counters: {', '.join(trig_bad)}, expected {rate:g} Hz (sync.rate_hz): is the "
                  f"{rig.desc.sync.source_part} trigger running and wired?") if trig_bad else
                 f"frame counters advance at {rate:g} Hz")]
    out.append(Check("sync mode", FAILED if sync_bad else OK,
                     f"{', '.join(sync_bad)}, expected {want_mode} (sync.boson_mode): run "
                     f"{_fix_command(rig, dev_dir)}" if sync_bad else f"{want_mode} as configured"))
    if want_telemetry:
        out.append(Check("telemetry", FAILED if telemetry_bad else OK,
                         f"{', '.join(telemetry_bad)}: the recording would carry no FFC status or a wrong one "
                         f"(on_device.thermal_telemetry_rows); run {_fix_command(rig, dev_dir)}" if telemetry_bad
                         else f"on, rows at the {EXPECTED_LOCATION}: the FFC status is recorded from them"))
    else:
        out.append(Check("telemetry", SKIPPED, "on_device.thermal_telemetry_rows is 0"))
    return out
