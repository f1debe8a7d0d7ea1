"""Which physical port holds which camera, from the camera itself: every port found is asked its serial
number over the serial link (bosonGetCameraSN), and the rig's left and right are mapped by that answer,
not by the USB serial string in the port's name (which is a hint: whether it always equals the camera's
serial is not verified on hardware, and a non-numeric one says nothing).

:func:`assign` detects a rig camera that no port answers as (missing, with what each port answered), two
ports answering the same serial (duplicate), and reports a port whose USB string names another serial
than the camera answers (swapped or renamed) and a camera the rig does not name (unknown). A port that
does not answer but whose USB string names a rig camera is still targeted, so the command reports that
camera's own error (no reply) instead of "not found".

:func:`survey` says the same of the whole rig without refusing anything, for the device's pre-flight
(firmware/device/bosonprobe.py): which port (and physical USB port) holds the left and the right camera,
and every problem at once, each a line.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from .client import BosonClient
from .codes import BosonError
from .discovery import Found, SelectionError, Target, describe_found

#: the open client on a port (operations.ClientPool.open: the command goes on with the same client)
Opener = Callable[[Target], BosonClient]


@dataclass(frozen=True)
class Identified:
    found: Found
    serial: int | None       # what the camera answered over its serial link (None: it did not)
    error: str | None = None

    def describe(self) -> str:
        said = f"answers SN {self.serial}" if self.serial is not None else f"does not answer ({self.error})"
        usb = f"USB serial {self.found.serial}" if self.found.serial is not None else "USB serial not numeric"
        where = f", USB port {Path(self.found.by_path).name}" if self.found.by_path else ""
        return f"{self.found.port} ({usb}{where}) {said}"


def identify(found: list[Found], open_client: Opener, per_camera) -> list[Identified]:
    """Ask every port with a serial device its serial number, all at once (``per_camera`` runs the work
    on each, as operations.per_camera does). The clients stay open: ``open_client`` owns them (a
    ClientPool), so the work after this reuses them and the serial is not asked again."""
    usable = [f for f in found if f.source != "usb"]

    def ask(f: Found) -> Identified:
        try:
            return Identified(f, open_client(Target(f.port, f.port, None, f.video)).camera_serial())
        except BosonError as exc:
            return Identified(f, None, str(exc))
    return per_camera(usable, ask)


def _rig_serials(rig) -> dict[str, int | None]:
    return {side: getattr(rig.desc.sensors.thermal, side).serial for side in ("left", "right")}


def _by_serial(identified: list[Identified]) -> dict[int, list[Identified]]:
    out: dict[int, list[Identified]] = {}
    for i in identified:
        if i.serial is not None:
            out.setdefault(i.serial, []).append(i)
    return out


def _duplicates(by_serial: dict[int, list[Identified]]) -> list[str]:
    return [f"SN {sn} is answered on {len(ports)} ports (" + ", ".join(p.found.where() for p in ports)
            + "): two cameras with one serial number?" for sn, ports in by_serial.items() if len(ports) > 1]


def _unset(rig, side: str) -> str:
    return (f"the {side} camera's serial number is not set: set sensors.thermal.{side}.serial in {rig.path} "
            f"(or pass --set sensors.thermal.{side}.serial=SN)")


def _seen(identified: list[Identified], found: list[Found]) -> str:
    return "; ".join(i.describe() for i in identified) or describe_found(found)


def assign(selection: str, rig, identified: list[Identified], found: list[Found]) -> tuple[list[Target], list[str]]:
    """Targets for ``--camera`` (left, right, all or a serial number) by the serials the cameras
    answered, and warnings (a USB string that names another serial, a camera the rig does not name).
    SelectionError (one line, naming the ports) for a missing or duplicated camera."""
    by_serial = _by_serial(identified)
    seen = _seen(identified, found)
    for line in _duplicates(by_serial):
        raise SelectionError(line)
    warnings = [f"{i.found.port}: its USB serial says {i.found.serial} but the camera answers SN {i.serial} "
                "(identified by the camera's answer)"
                for i in identified if i.serial is not None and i.found.serial not in (None, i.serial)]
    rig_sns = _rig_serials(rig)
    if selection in ("left", "right"):
        wanted = {selection: rig_sns[selection]}
    elif selection.isdigit():
        wanted = {f"SN {selection}": int(selection)}
    elif selection == "all" and all(sn is not None for sn in rig_sns.values()):
        wanted = dict(rig_sns)
        named = set(rig_sns.values())
        warnings += [f"{i.found.port} holds SN {i.serial}, which the rig does not name "
                     "(sensors.thermal.left/right.serial): left alone" for i in identified
                     if i.serial is not None and i.serial not in named]
    else:   # all, serials not set: every camera that answers
        known = {sn: side for side, sn in rig_sns.items() if sn is not None}
        def label(i: Identified) -> str:
            sn = i.serial if i.serial is not None else i.found.serial
            return known.get(sn, f"SN {sn}" if sn is not None else i.found.port)
        # a silent port stays a target: the command reports its own error for it (no reply)
        targets = [Target(label(i), i.found.port, i.serial, i.found.video) for i in identified]
        if not targets:
            raise SelectionError(describe_found(found))
        return targets, warnings
    targets = []
    for label, sn in wanted.items():
        if sn is None:
            raise SelectionError(_unset(rig, label))
        if sn not in by_serial:
            silent = [i for i in identified if i.serial is None and i.found.serial == sn]
            if len(silent) == 1:   # its port names it but it did not answer: the command reports that camera
                targets.append(Target(label, silent[0].found.port, sn, silent[0].found.video))
                continue
            who = f"{label} camera (SN {sn})" if not label.startswith("SN") else label
            if any(f.serial == sn and f.source == "usb" for f in found):
                raise SelectionError(f"{who} is on USB but has no serial port (cdc_acm driver or permissions?); "
                                     f"{seen}")
            raise SelectionError(f"{who} not found: no port answers with this serial; {seen}")
        i = by_serial[sn][0]
        targets.append(Target(label, i.found.port, sn, i.found.video))
    return targets, warnings


@dataclass
class RigSurvey:
    """Which port holds each rig camera, from what every port answered (:func:`survey`)."""
    cameras: dict[str, Identified] = field(default_factory=dict)   # side -> the one port answering its serial
    problems: list[str] = field(default_factory=list)   # the rig cannot be trusted to record: one line each
    notes: list[str] = field(default_factory=list)      # worth knowing, not wrong: an unknown camera, a silent port


def survey(rig, identified: list[Identified], found: list[Found]) -> RigSurvey:
    """Left and right by the serial each port answered, and every problem at once: a rig serial not set,
    a rig camera no port answers as (missing), one serial on two ports (duplicate), and a rig camera on a
    port whose USB serial string names another serial (swapped or renamed: udev names the video nodes by
    that string, so a recording would file the images under the wrong camera)."""
    out = RigSurvey()
    rig_sns = _rig_serials(rig)
    by_serial = _by_serial(identified)
    out.problems += _duplicates(by_serial)
    for side, sn in rig_sns.items():
        if sn is None:
            out.problems.append(_unset(rig, side))
        elif sn not in by_serial:
            out.problems.append(f"{side} camera (SN {sn}) not found: no port answers with this serial; "
                                f"{_seen(identified, found)}")
        elif len(by_serial[sn]) == 1:
            out.cameras[side] = by_serial[sn][0]
    side_of = {sn: side for side, sn in rig_sns.items() if sn is not None}
    for side, i in out.cameras.items():
        usb = i.found.serial
        if usb is not None and usb != i.serial:
            other = f"the {side_of[usb]} camera's SN {usb}" if usb in side_of else f"SN {usb}"
            out.problems.append(f"{side} camera (SN {i.serial}) is on {i.found.where()}, whose USB serial string "
                                f"names {other}: udev names the video nodes by that string, so its images would be "
                                "recorded as another camera's")
    out.notes += [f"{i.found.where()} holds SN {i.serial}, which the rig does not name" for i in identified
                  if i.serial is not None and i.serial not in side_of]
    out.notes += [f"{i.found.where()} does not answer ({i.error})" for i in identified if i.serial is None]
    return out
