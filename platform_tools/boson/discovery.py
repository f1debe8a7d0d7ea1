"""Which Bosons are connected, and which one is the rig's left or right camera.

Sources, merged by serial number:
- the by-id folder (``/dev/serial/by-id``, or ``$PLATFORM_TOOLS_BOSON_BY_ID``, where the emulator
  publishes its links): ``usb-FLIR_Boson_<SN>-if00``;
- pyserial's port list, filtered on USB 09CB:4007 (ports udev gave no by-id link);
- pyusb, also filtered on 09CB:4007: a camera on the bus whose serial port is missing (driver,
  permissions) is reported so the user knows it is there;
- the video device from ``/dev/v4l/by-id`` (or ``$PLATFORM_TOOLS_BOSON_V4L_BY_ID``);
- the physical USB port from ``/dev/serial/by-path`` (or ``$PLATFORM_TOOLS_BOSON_BY_PATH``): the link
  there that leads to the same device, so a report can say which socket holds which camera.
"""
from __future__ import annotations

import logging
import os
import re
from dataclasses import asdict, dataclass
from pathlib import Path

log = logging.getLogger(__name__)

USB_VID, USB_PID = 0x09CB, 0x4007
BY_ID_ENV = "PLATFORM_TOOLS_BOSON_BY_ID"
V4L_ENV = "PLATFORM_TOOLS_BOSON_V4L_BY_ID"
BY_PATH_ENV = "PLATFORM_TOOLS_BOSON_BY_PATH"
_SERIAL_LINK = re.compile(r"^usb-FLIR_Boson_(.+)-if0?0$")   # the USB serial string: digits, or not
_VIDEO_LINK = "usb-FLIR_Boson_{sn}-video-index0"


def by_id_dir() -> Path:
    return Path(os.environ.get(BY_ID_ENV) or "/dev/serial/by-id")


def v4l_dir() -> Path:
    return Path(os.environ.get(V4L_ENV) or "/dev/v4l/by-id")


def by_path_dir() -> Path:
    return Path(os.environ.get(BY_PATH_ENV) or "/dev/serial/by-path")


def by_path_for(device: str) -> str | None:
    """The /dev/serial/by-path link (the physical USB port) that leads to ``device``, if any."""
    folder = by_path_dir()
    try:
        names = sorted(os.listdir(folder))
    except OSError:
        return None
    for name in names:
        if device and _target(folder / name) == device:
            return str(folder / name)
    return None


@dataclass(frozen=True)
class Found:
    serial: int | None      # the USB serial string (by-id name), if numeric: a hint; identity.py asks the camera
    port: str               # the name to open: the by-id link when there is one
    device: str             # what it resolves to (/dev/ttyACM0, /dev/pts/5)
    video: str | None       # /dev/videoN, when its by-id link exists
    source: str             # "by-id", "port-list", "udev" (a rig's udev name) or "usb" (on the bus, no serial port)
    by_path: str | None = None   # the /dev/serial/by-path link: which physical USB port

    def to_dict(self) -> dict:
        return asdict(self)

    def describe(self) -> str:
        sn = f"SN {self.serial}" if self.serial is not None else "SN unknown"
        return f"{sn} at {self.port}" + (f" (no serial port: {self.source})" if self.source == "usb" else "")

    def where(self) -> str:
        """The port, and the physical USB port behind it when known."""
        return self.port + (f" (USB port {Path(self.by_path).name})" if self.by_path else "")


def _target(link) -> str | None:
    """Where a udev link points now; None when it is gone (udev removes links while a camera re-enumerates,
    also between our exists() and realpath())."""
    try:
        return os.path.realpath(link) if os.path.exists(link) else None
    except OSError:
        return None


def _video_for(serial: int | None) -> str | None:
    if serial is None:
        return None
    link = v4l_dir() / _VIDEO_LINK.format(sn=serial)
    return _target(link)


def _from_by_id() -> list[Found]:
    folder = by_id_dir()
    try:
        names = sorted(os.listdir(folder))
    except OSError:
        return []
    out = []
    for name in names:
        m = _SERIAL_LINK.match(name)
        if not m:
            continue
        link = folder / name
        target = _target(link)
        if target is None:             # dangling: the camera is re-enumerating
            continue
        sn = int(m.group(1)) if m.group(1).isdigit() else None
        out.append(Found(sn, str(link), target, _video_for(sn), "by-id", by_path_for(target)))
    return out


def _from_port_list() -> list[Found]:
    try:
        from serial.tools import list_ports
        ports = list(list_ports.comports())
    except Exception as exc:   # pyserial's listing reads sysfs; never let it stop discovery
        log.debug("pyserial port listing failed: %s", exc)
        return []
    out = []
    for p in ports:
        if (p.vid, p.pid) != (USB_VID, USB_PID):
            continue
        sn = int(p.serial_number) if p.serial_number and p.serial_number.isdigit() else None
        device = os.path.realpath(p.device)
        out.append(Found(sn, p.device, device, _video_for(sn), "port-list", by_path_for(device)))
    return out


def _from_usb() -> list[Found]:
    try:
        import usb.core
        devices = list(usb.core.find(find_all=True, idVendor=USB_VID, idProduct=USB_PID))
    except Exception as exc:   # no libusb backend, no permission on /dev/bus/usb
        log.debug("pyusb listing unavailable: %s", exc)
        return []
    out = []
    for dev in devices:
        sn = None
        try:
            import usb.util
            text = usb.util.get_string(dev, dev.iSerialNumber) if dev.iSerialNumber else None
            sn = int(text) if text and text.isdigit() else None
        except Exception:
            pass
        out.append(Found(sn, f"usb bus {dev.bus} address {dev.address}", "", _video_for(sn), "usb"))
    return out


def discover() -> list[Found]:
    """Every Boson found, by-id links first; a camera seen by several sources is listed once."""
    found = _from_by_id()
    seen_devices = {f.device for f in found}
    seen_serials = {f.serial for f in found if f.serial is not None}
    for f in _from_port_list():
        if f.device not in seen_devices and (f.serial is None or f.serial not in seen_serials):
            found.append(f)
            seen_devices.add(f.device)
            if f.serial is not None:
                seen_serials.add(f.serial)
    for f in _from_usb():
        if f.serial is None or f.serial not in seen_serials:
            found.append(f)
    return found


def udev_ports(rig, dev_dir: Path, found: list[Found]) -> tuple[list[Found], dict[str, str]]:
    """The rig's udev names of the serial ports (``dev_dir/<device_name>_serial``, what the device's
    containers are given instead of /dev/serial/by-id) that lead to a device ``found`` does not hold, one
    Found each (source "udev"); and side -> the device each existing name leads to."""
    devices = {f.device for f in found if f.source != "usb"}
    extra: list[Found] = []
    udev: dict[str, str] = {}
    for side in ("left", "right"):
        name = dev_dir / rig.boson_device_nodes(side)["serial"]
        device = _target(name)
        if device is None:
            continue
        udev[side] = device
        if device not in devices:
            extra.append(Found(None, str(name), device, None, "udev", by_path_for(device)))
            devices.add(device)
    return extra, udev


def describe_found(found: list[Found]) -> str:
    usable = [f for f in found]
    if not usable:
        return (f"no Boson found (looked in {by_id_dir()}, the serial port list and USB for "
                f"{USB_VID:04X}:{USB_PID:04X}); is it plugged in?")
    return "found: " + "; ".join(f.describe() for f in usable)


# ---------------------------------------------------------------------------- selection
@dataclass(frozen=True)
class Target:
    label: str              # left, right, or "SN <n>" / the port
    port: str
    serial: int | None      # what bosonGetCameraSN must answer (None: not known in advance)
    video: str | None = None


class SelectionError(Exception):
    """The selection cannot be satisfied; ``str()`` is one line naming the key or camera."""


def _rig_serial(rig, side: str) -> int:
    sn = getattr(rig.desc.sensors.thermal, side).serial
    if sn is None:
        raise SelectionError(
            f"the {side} camera's serial number is not set: set sensors.thermal.{side}.serial in {rig.path} "
            f"(or pass --set sensors.thermal.{side}.serial=SN; `platform_tools boson-info`, or `rig-device doctor` "
            "on the device, lists the serials)")
    return sn


def _pick(found: list[Found], serial: int, label: str) -> Target:
    matches = [f for f in found if f.serial == serial]
    usable = [f for f in matches if f.source != "usb"]
    if not usable:
        if matches:
            raise SelectionError(f"{label} camera (SN {serial}) is on USB but has no serial port "
                                 f"(cdc_acm driver or permissions?); {describe_found(found)}")
        raise SelectionError(f"{label} camera (SN {serial}) not found; {describe_found(found)}")
    if len(usable) > 1:
        raise SelectionError(f"{label} camera (SN {serial}) is ambiguous: "
                             + ", ".join(f.port for f in usable))
    f = usable[0]
    return Target(label, f.port, serial, f.video)


def select_targets(selection: str, rig, found: list[Found], port: str | None = None) -> list[Target]:
    """Turn ``--camera`` (left, right, all or a serial number) and ``--port`` into targets."""
    if port is not None:
        serial = None
        label = port
        if selection in ("left", "right"):
            serial, label = _rig_serial(rig, selection), selection
        elif selection.isdigit():
            serial, label = int(selection), f"SN {selection}"
        return [Target(label, port, serial)]
    if selection in ("left", "right"):
        return [_pick(found, _rig_serial(rig, selection), selection)]
    if selection.isdigit():
        return [_pick(found, int(selection), f"SN {selection}")]
    if selection != "all":
        raise SelectionError(f"--camera {selection!r}: use left, right, all or a serial number")
    sides = {s: getattr(rig.desc.sensors.thermal, s).serial for s in ("left", "right")}
    if all(sn is not None for sn in sides.values()):
        return [_pick(found, sn, side) for side, sn in sides.items()]
    usable = [f for f in found if f.source != "usb"]
    if not usable:
        raise SelectionError(describe_found(found))
    known = {sn: side for side, sn in sides.items() if sn is not None}
    return [Target(known.get(f.serial, f"SN {f.serial}" if f.serial is not None else f.port),
                   f.port, f.serial, f.video) for f in usable]
