"""The V4L2 controls usb_cam writes to a Boson, and how the rendered stack keeps it from writing any the rig
did not ask for (issue 18, item 3).

usb_cam (ros-drivers/usb_cam, ROS 2) writes camera controls at start-up from its parameters: with
``brightness``, ``autoexposure`` and ``auto_white_balance`` unset it writes its defaults (50, true, true) to the
device (upstream-tartanrgbt.md). A Boson is configured over its serial port (`platform_tools boson-config`);
a UVC control written behind its back changes what was configured. So:

1. the rendered parameter file sets every integer control to -1 unless the rig asks for it
   (``on_device.thermal_v4l2_controls``; usb_cam writes an integer control only when it is >= 0: **read from
   the usb_cam source from memory, not re-verified here**);
2. the boolean ones (``autoexposure``, ``auto_white_balance``, ``autofocus``) cannot be unset: usb_cam writes
   one state or the other. usb_cam writes controls by running ``v4l2-ctl -c name=value`` (again from memory of
   its source), so the thermal containers get ``bin/v4l2-ctl`` first on their PATH
   (:mod:`firmware.device.v4l2guard`): it refuses every control the rig did not ask for and passes the rest
   to the real ``v4l2-ctl``. If a usb_cam release writes by ioctl instead, the guard sees nothing:
   ``doctor --bring-up`` does not measure this (the video controls are not read back); say so in a report.
3. ``firmware check`` (rule ``v4l2 controls``) fails a rendered thermal configuration that would write a
   control the rig did not ask for.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from platform_tools.rig import Rig
from platform_tools.rig.checks import FAILED, OK, Check
from platform_tools.rig.yamlsource import safe_load


@dataclass(frozen=True)
class Control:
    param: str              # the usb_cam parameter
    kind: type              # int or bool
    unset: int | None       # the value that makes usb_cam write nothing (None: no such value)
    v4l2: tuple[str, ...]   # the V4L2 controls it writes (names as usb_cam passes them to v4l2-ctl)


#: usb_cam's control parameters (spelled as usb_cam spells them); the V4L2 control names are the ones usb_cam
#: passes to v4l2-ctl (older kernel names: newer kernels also accept auto_exposure, white_balance_automatic)
CONTROLS = {c.param: c for c in (
    Control("brightness", int, -1, ("brightness",)),
    Control("contrast", int, -1, ("contrast",)),
    Control("saturation", int, -1, ("saturation",)),
    Control("sharpness", int, -1, ("sharpness",)),
    Control("gain", int, -1, ("gain",)),
    Control("white_balance", int, -1, ("white_balance_temperature",)),
    Control("exposure", int, -1, ("exposure_absolute",)),
    Control("focus", int, -1, ("focus_absolute",)),
    Control("auto_white_balance", bool, None, ("white_balance_temperature_auto",)),
    Control("autoexposure", bool, None, ("exposure_auto",)),
    Control("autofocus", bool, None, ("focus_auto",)),
)}
#: usb_cam's defaults of the boolean ones (what it writes when they are unset)
BOOL_DEFAULTS = {"auto_white_balance": True, "autoexposure": True, "autofocus": False}
#: where the thermal containers find the guard: before /usr/bin on the ROS images' PATH
GUARD_MOUNT = "/usr/local/bin/v4l2-ctl"
GUARD_FILE = "bin/v4l2-ctl"


def asked(rig: Rig) -> dict:
    """The rig's ``on_device.thermal_v4l2_controls``, checked: ValueError naming the key otherwise."""
    out = {}
    for name, value in rig.desc.on_device.thermal_v4l2_controls.items():
        if name not in CONTROLS:
            raise ValueError(f"on_device.thermal_v4l2_controls.{name}: not a usb_cam control parameter; "
                             f"known: {', '.join(CONTROLS)}")
        c = CONTROLS[name]
        if (c.kind is bool) != isinstance(value, bool) or (c.kind is int and value < 0):
            raise ValueError(f"on_device.thermal_v4l2_controls.{name}: {value!r} is not a "
                             f"{'true/false' if c.kind is bool else 'non-negative integer'}")
        out[name] = value
    return out


def allowed_v4l2(rig: Rig) -> set[str]:
    """The V4L2 control names the guard lets through: those of the parameters the rig asks for."""
    return {v for name in asked(rig) for v in CONTROLS[name].v4l2}


def rendered_params(rig: Rig) -> dict:
    """The usb_cam control parameters of the rendered thermal configuration, every one of them explicit."""
    want = asked(rig)
    return {name: want.get(name, c.unset if c.kind is int else BOOL_DEFAULTS[name]) for name, c in CONTROLS.items()}


def writes(params: dict) -> set[str]:
    """The V4L2 controls usb_cam would try to write with these parameters (its semantics: an integer control
    when >= 0 or absent, since its default is then used; a boolean one always)."""
    out = set()
    for name, c in CONTROLS.items():
        if c.kind is bool or name not in params or params[name] is None or int(params[name]) >= 0:
            out.update(c.v4l2)
    return out


def check_controls(folder: Path, rig: Rig, thermal_names: list[str]) -> Check:
    """No rendered thermal configuration writes a V4L2 control the rig did not ask for: an integer control
    set (or left to usb_cam's default) fails; a boolean one passes only when the guard is mounted."""
    allowed = allowed_v4l2(rig)
    compose = safe_load((folder / "compose.yaml").read_text()) or {}
    guard_ok = (folder / GUARD_FILE).is_file()
    problems = []
    for name in thermal_names:
        p = (safe_load((folder / "config" / f"{name}.yaml").read_text()) or {})
        p = p.get("/**", {}).get("ros__parameters", {})
        vols = [str(v) for v in compose.get("services", {}).get(name, {}).get("volumes", [])]
        guarded = guard_ok and any(v.split(":")[1:2] == [GUARD_MOUNT] for v in vols)
        for ctl in sorted(writes(p) - allowed):
            param = next(n for n, c in CONTROLS.items() if ctl in c.v4l2)
            if CONTROLS[param].kind is int:
                problems.append(f"config/{name}.yaml: {param} {p.get(param, 'unset (usb_cam default)')} "
                                f"writes {ctl}, not in on_device.thermal_v4l2_controls")
            elif not guarded:
                problems.append(f"{name}: usb_cam writes {ctl} ({param}) and no {GUARD_FILE} is mounted at "
                                f"{GUARD_MOUNT} to refuse it")
    if problems:
        return Check("v4l2 controls", FAILED, "; ".join(problems))
    return Check("v4l2 controls", OK, f"{len(thermal_names)} thermal configs write "
                                      f"{', '.join(sorted(allowed)) or 'no V4L2 control'} (the rest refused by "
                                      f"{GUARD_FILE})")
