"""Which physical port holds which camera, from the camera itself: every port found is asked its serial
number over the serial link (bosonGetCameraSN), and the rig's left and right are mapped by that answer,
not by the USB serial string in the port's name (which is a hint: whether it always equals the camera's
serial is not verified on hardware, and a non-numeric one says nothing).

:func:`assign` detects a rig camera that no port answers as (missing, with what each port answered), two
ports answering the same serial (duplicate), and reports a port whose USB string names another serial
than the camera answers (swapped or renamed) and a camera the rig does not name (unknown). A port that
does not answer but whose USB string names a rig camera is still targeted, so the command reports that
camera's own error (no reply) instead of "not found".
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from . import commands as C
from .client import BosonClient
from .codes import BosonError
from .discovery import Found, SelectionError, Target, describe_found

#: opens a client on a port (operations.open_client with the command's timeouts)
Opener = Callable[[Target], BosonClient]


@dataclass(frozen=True)
class Identified:
    found: Found
    serial: int | None       # what the camera answered over its serial link (None: it did not)
    error: str | None = None

    def describe(self) -> str:
        said = f"answers SN {self.serial}" if self.serial is not None else f"does not answer ({self.error})"
        usb = f"USB serial {self.found.serial}" if self.found.serial is not None else "USB serial not numeric"
        return f"{self.found.port} ({usb}) {said}"


def identify(found: list[Found], open_client: Opener, per_camera) -> list[Identified]:
    """Ask every port with a serial device its serial number, all at once (``per_camera`` runs the work
    on each, as operations.per_camera does)."""
    usable = [f for f in found if f.source != "usb"]

    def ask(f: Found) -> Identified:
        try:
            with open_client(Target(f.port, f.port, None, f.video)) as client:
                return Identified(f, client.call(C.GET_CAMERA_SN))
        except BosonError as exc:
            return Identified(f, None, str(exc))
    return per_camera(usable, ask)


def _rig_serials(rig) -> dict[str, int | None]:
    return {side: getattr(rig.desc.sensors.thermal, side).serial for side in ("left", "right")}


def assign(selection: str, rig, identified: list[Identified], found: list[Found]) -> tuple[list[Target], list[str]]:
    """Targets for ``--camera`` (left, right, all or a serial number) by the serials the cameras
    answered, and warnings (a USB string that names another serial, a camera the rig does not name).
    SelectionError (one line, naming the ports) for a missing or duplicated camera."""
    by_serial: dict[int, list[Identified]] = {}
    for i in identified:
        if i.serial is not None:
            by_serial.setdefault(i.serial, []).append(i)
    seen = "; ".join(i.describe() for i in identified) or describe_found(found)
    for sn, ports in by_serial.items():
        if len(ports) > 1:
            raise SelectionError(f"SN {sn} is answered on {len(ports)} ports ("
                                 + ", ".join(p.found.port for p in ports) + "): two cameras with one serial number?")
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
            raise SelectionError(f"the {label} camera's serial number is not set: set sensors.thermal.{label}.serial "
                                 f"in {rig.path} (or pass --set sensors.thermal.{label}.serial=SN)")
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
