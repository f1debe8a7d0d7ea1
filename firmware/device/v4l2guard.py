"""`v4l2-ctl` as the thermal containers see it: refuses to set a V4L2 control the rig did not ask for.

usb_cam writes camera controls by running ``v4l2-ctl --device=... -c name=value`` (firmware/v4l2.py); the
rendered ``bin/v4l2-ctl`` (first on the containers' PATH) runs

    python3 -m firmware.device.v4l2guard --allow brightness,exposure_auto -- <v4l2-ctl arguments>

A call setting any control outside ``--allow`` prints one line to stderr and exits 1 without touching the
device (usb_cam logs the failure and streams on); every other call runs the real v4l2-ctl
(``$V4L2_CTL_REAL``, default /usr/bin/v4l2-ctl) with the same arguments.
"""
from __future__ import annotations

import os
import sys

REAL = "/usr/bin/v4l2-ctl"


def controls_set(argv: list[str]) -> list[str]:
    """The names of the controls a v4l2-ctl command line sets (-c / --set-ctrl, comma-separated lists)."""
    names, i = [], 0
    while i < len(argv):
        a = argv[i]
        value = None
        if a in ("-c", "--set-ctrl") and i + 1 < len(argv):
            value, i = argv[i + 1], i + 1
        elif a.startswith("--set-ctrl="):
            value = a.split("=", 1)[1]
        elif a.startswith("-c") and len(a) > 2:
            value = a[2:]
        if value is not None:
            names += [kv.split("=", 1)[0].strip() for kv in value.split(",") if kv.strip()]
        i += 1
    return names


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    allow: set[str] = set()
    if argv[:1] == ["--allow"]:
        allow = {n for n in argv[1].split(",") if n} if len(argv) > 1 else set()
        argv = argv[2:]
    if argv[:1] == ["--"]:
        argv = argv[1:]
    refused = [n for n in controls_set(argv) if n not in allow]
    if refused:
        print(f"v4l2-ctl (rgbt-rig guard): refused to set {', '.join(refused)}: not in "
              f"on_device.thermal_v4l2_controls; the Boson keeps its own settings", file=sys.stderr)
        return 1
    real = os.environ.get("V4L2_CTL_REAL", REAL)
    os.execv(real, [real, *argv])
    return 127  # not reached


if __name__ == "__main__":
    sys.exit(main())
