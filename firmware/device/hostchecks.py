"""Checks of the Orin itself that every pre-flight runs (`rig-device doctor`, the recorder before each
recording), not only the bring-up:

gpio pinmux   the record button's and LED's header pins are GPIOs in the kernel's pinmux table
              (/sys/kernel/debug/pinctrl/*/pinmux-pins: root and debugfs). On JetPack 6 the 40-pin header
              pins need a pinmux change (jetson-io or a flashed pinmux) before GPIO works on them
              (NVIDIA/jetson-gpio issue 114)
host clock    the host clock is disciplined before recording: `chronyc tracking` (chronyd answers it over
              127.0.0.1 to the host-network containers) leap status Normal, stratum below 16, |system
              time offset| at most MAX_CLOCK_OFFSET_S; a clock stepped during a recording moves the ZED
              and IMU stamps but not usb_cam's (docs/on-device.md)

A check that cannot measure its fact here is skipped with "not measurable here: why", never passed.
"""
from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

from platform_tools.rig import Rig
from platform_tools.rig.checks import FAILED, OK, SKIPPED, Check

NOT_HERE = "not measurable here: "
#: largest |host clock offset| from its reference that passes (ZED and thermal stamps pair at the ms scale)
MAX_CLOCK_OFFSET_S = 1e-3
#: NTP's "unsynchronised" stratum
UNSYNCHRONISED_STRATUM = 16
#: the AGX Orin developer kit's 40-pin header (BOARD numbering) -> SoC pin (NVIDIA's pinmux sheet, second-hand)
ORIN_BOARD_PINS = {29: "PQ.05", 31: "PQ.06"}


def _pin_regex(soc: str) -> re.Pattern:
    port, num = re.fullmatch(r"P([A-Z]+)\.(\d+)", soc).groups()
    return re.compile(rf"\(\S*p{port.lower()}\.?0?{int(num)}\)", re.IGNORECASE)


def check_pinmux(rig: Rig, root: Path) -> Check:
    b = rig.desc.recording.button
    pins = {"button": b.gpio_pin, "LED": b.led_pin}
    if b.pin_numbering != "BOARD" or any(p not in ORIN_BOARD_PINS for p in pins.values()):
        return Check("gpio pinmux", SKIPPED, NOT_HERE + f"no SoC name known for pins {pins} ({b.pin_numbering})")
    tables = sorted((root / "sys" / "kernel" / "debug" / "pinctrl").glob("*/pinmux-pins"))
    if not tables:
        return Check("gpio pinmux", SKIPPED, NOT_HERE + "no /sys/kernel/debug/pinctrl/*/pinmux-pins (run as root "
                                             "with debugfs mounted)")
    lines = [ln for t in tables for ln in t.read_text().splitlines()]
    bad, good = [], []
    for what, pin in pins.items():
        soc = ORIN_BOARD_PINS[pin]
        hit = [ln for ln in lines if _pin_regex(soc).search(ln)]
        if not hit:
            bad.append(f"{what} pin {pin} ({soc}): not in the pinmux table")
        elif not re.search(r"\.gpio\b|function\s+gpio", hit[0].split("):", 1)[-1], re.I):   # claimed by the GPIO driver
            bad.append(f"{what} pin {pin} ({soc}) is not a GPIO: {hit[0].strip()!r} (flash a pinmux: jetson-io)")
        else:
            good.append(f"{what} pin {pin} ({soc}): {hit[0].strip()}")
    return Check("gpio pinmux", FAILED if bad else OK, "; ".join(bad or good))


def check_host_clock() -> Check:
    if shutil.which("chronyc") is None:
        return Check("host clock", SKIPPED, NOT_HERE + "chronyc is not installed (another NTP or PTP daemon: check "
                                           "it by hand)")
    try:
        r = subprocess.run(["chronyc", "tracking"], capture_output=True, text=True, timeout=10)
    except subprocess.TimeoutExpired:
        return Check("host clock", FAILED, "chronyc tracking: no answer from chronyd within 10 s")
    leap = re.search(r"^Leap status\s*:\s*(.+?)\s*$", r.stdout, re.M)
    off = re.search(r"^System time\s*:\s*([\d.]+) seconds (fast|slow)", r.stdout, re.M)
    stratum = re.search(r"^Stratum\s*:\s*(\d+)", r.stdout, re.M)
    if r.returncode != 0 or leap is None or off is None:
        return Check("host clock", FAILED, f"chronyc tracking: {(r.stderr or r.stdout).strip()[:120] or 'no output'}")
    offset = float(off.group(1))
    why = []
    if leap.group(1) != "Normal":
        why.append("the clock is not synchronised (leap status must be Normal)")
    if stratum and int(stratum.group(1)) >= UNSYNCHRONISED_STRATUM:
        why.append(f"stratum {stratum.group(1)} (unsynchronised)")
    if offset > MAX_CLOCK_OFFSET_S:
        why.append(f"offset above {MAX_CLOCK_OFFSET_S:g} s")
    detail = (f"leap status {leap.group(1)}, " + (f"stratum {stratum.group(1)}, " if stratum else "")
              + f"system time {offset:.6f} s {off.group(2)}")
    if why:
        return Check("host clock", FAILED, detail + ": " + "; ".join(why) + " (wait for chronyd, or `chronyc "
                                           "makestep` before recording: a step during a recording shifts the "
                                           "thermal stamps)")
    return Check("host clock", OK, detail)


def run(rig: Rig, root: Path = Path("/")) -> list[Check]:
    return [check_pinmux(rig, root), check_host_clock()]
