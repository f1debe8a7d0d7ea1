"""The rig's electrical design, computed from the parts: power budget, battery current, fuse size, and the
checks that the switch, fuse, converter and sync trigger fit it.

Every number is read from the rig description (each part's ``power_w``, ``supply_v``, ``output_v``,
``rating_a``, ``rating_dc_v``, ``efficiency``, ``cutoff_v``, ``sync_input_v``, the converter's
``dims.input_fuse_max_a`` where its datasheet gives it, and ``sync.level_v``); the
only constants here are engineering rules (fuse margin, the ATO value series, the Jetson header's 3.3 V
logic and what its pins may source, with that figure's provenance), named below; the button LED's forward
voltage and series resistor are its ``dims`` where the rig gives them. The battery current is taken at the pack's cut-off voltage: the lowest voltage the
load sees, so the highest current for the same power.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping

from cad.bought.base import part_of_kind

#: a fuse carries its rated current indefinitely: size it this much above the continuous load
FUSE_MARGIN = 1.25
#: ATO / ATC blade fuse values (A), the standard series
ATO_VALUES_A = (1, 2, 3, 5, 7.5, 10, 15, 20, 25, 30, 35, 40)
#: the Jetson AGX Orin devkit's 40-pin header GPIOs are 3.3 V logic (NVIDIA devkit carrier board spec)
GPIO_V = 3.3
#: What one header GPIO may source. No NVIDIA figure for the AGX Orin devkit's 40-pin header drive was found
#: (shared/reference/*.md; the search tool's pages and issues). Jetson devkits bring the header out through
#: TXB0108-type auto-direction level shifters (an NVIDIA forum measurement on a Xavier NX devkit: the pin fell
#: to 2.0 V on 6.4 kOhm, 0.31 mA, forums.developer.nvidia.cn/t/jetson-xavier-nano/27654; NOT confirmed for the
#: AGX Orin devkit: read its carrier board specification). TI's TXB0108 datasheet (SCES643I, application
#: information, ti.com) puts a 4 kOhm resistor in series with each output and asks for external loads above
#: 50 kOhm: the translator vendor's figure, used here with that provenance.
TXB0108_MIN_LOAD_KOHM = 50.0
GPIO_SOURCE_MAX_MA = GPIO_V / TXB0108_MIN_LOAD_KOHM
GPIO_SOURCE_SOURCE = ("TI TXB0108 datasheet SCES643I: external load > 50 kOhm; the devkit's header level shifter, "
                      "no NVIDIA AGX Orin figure found")


@dataclass(frozen=True)
class Result:
    name: str
    ok: bool
    text: str


@dataclass(frozen=True)
class Budget:
    loads_w: Mapping[str, tuple[int, float]]   # part id -> (count, watts each)
    load_w: float            # at the converter's output
    battery_w: float         # drawn from the battery (load / efficiency)
    cutoff_v: float
    max_v: float
    battery_a: float         # at the cut-off voltage: the worst case
    battery_a_full: float    # at the pack's full voltage
    converter_a: float       # at the converter's output voltage
    fuse_a: float            # the smallest ATO value above FUSE_MARGIN x battery_a


def power_counts(asm) -> dict[str, int]:
    """How many of each powered part the CAD assembly places."""
    counts: dict[str, int] = {}
    for n in asm.nodes:
        if n.category == "bought" and n.part_id in asm.rig.desc.parts and asm.rig.part(n.part_id).power_w is not None:
            counts[n.part_id] = counts.get(n.part_id, 0) + 1
    return counts


def budget(rig, counts: Mapping[str, int]) -> Budget:
    """The power budget of ``counts`` (part id -> how many) on the rig's battery and converter."""
    bat, conv = rig.part(part_of_kind(rig, "battery")), rig.part(part_of_kind(rig, "converter"))
    loads = {pid: (k, rig.part(pid).power_w.value) for pid, k in counts.items()
             if k and rig.part(pid).power_w is not None}
    load = sum(k * w for k, w in loads.values())
    eff = conv.efficiency.value if conv.efficiency is not None else 1.0
    cutoff = bat.cutoff_v.value if bat.cutoff_v is not None else bat.output_v.min
    battery_w = load / eff
    amps = battery_w / cutoff
    fuse = next((v for v in ATO_VALUES_A if v >= FUSE_MARGIN * amps), math.inf)
    return Budget(loads_w=loads, load_w=load, battery_w=battery_w, cutoff_v=cutoff, max_v=bat.output_v.max,
                  battery_a=amps, battery_a_full=battery_w / bat.output_v.max,
                  converter_a=load / conv.output_v.max, fuse_a=fuse)


def _rated(part, pid: str, what: str) -> tuple[float | None, float | None, str]:
    a = part.rating_a.value if part.rating_a is not None else None
    v = part.rating_dc_v.value if part.rating_dc_v is not None else None
    missing = [k for k, x in (("rating_a", a), ("rating_dc_v", v)) if x is None]
    return a, v, (f"parts.{pid}.{' and '.join(missing)} not given: the {what} cannot be checked" if missing else "")


def power_checks(rig, counts: Mapping[str, int]) -> list[Result]:
    """The switch and fuse against the computed battery current, the converter against its output current."""
    b = budget(rig, counts)
    sw_id, fu_id, cv_id = (part_of_kind(rig, k) for k in ("switch", "fuse", "converter"))
    out = [Result("power budget", True,
                  f"loads {b.load_w:.1f} W (" + ", ".join(f"{k} x {pid} {w:g} W" for pid, (k, w) in b.loads_w.items())
                  + f"), {b.battery_w:.1f} W from the battery: {b.battery_a:.2f} A at the {b.cutoff_v:g} V cut-off, "
                  f"{b.battery_a_full:.2f} A at {b.max_v:g} V; fuse {b.fuse_a:g} A (>= {FUSE_MARGIN:g} x "
                  f"{b.battery_a:.2f} A)")]
    sa, sv, miss = _rated(rig.part(sw_id), sw_id, "switch")
    if miss:
        out.append(Result("switch rating", False, miss))
    else:
        ok = sa >= b.fuse_a and sv >= b.max_v
        out.append(Result("switch rating", ok, f"switch {sw_id} rated {sa:g} A at {sv:g} V DC "
                          + ("covers" if ok else "does not cover")
                          + f" the fuse's {b.fuse_a:g} A (load {b.battery_a:.2f} A) at up to {b.max_v:g} V"))
    fa, fv, miss = _rated(rig.part(fu_id), fu_id, "fuse")
    if miss:
        out.append(Result("fuse rating", False, miss))
    else:
        ok = FUSE_MARGIN * b.battery_a <= fa and fv >= b.max_v and (sa is None or fa <= sa)
        out.append(Result("fuse rating", ok, f"fuse {fu_id} {fa:g} A, {fv:g} V DC: "
                          + ("" if ok else "NOT ")
                          + f"between {FUSE_MARGIN:g} x the {b.battery_a:.2f} A load and the switch's rating, "
                            f"rated for {b.max_v:g} V"))
    conv = rig.part(cv_id)
    ca = conv.rating_a.value if conv.rating_a is not None else None
    out.append(Result("converter rating", ca is not None and ca >= b.converter_a,
                      f"converter {cv_id} output {ca if ca is not None else '(rating_a not given)'} A for "
                      f"{b.converter_a:.2f} A at {conv.output_v.max:g} V"))
    bat = rig.part(part_of_kind(rig, "battery"))
    out.append(Result("under-voltage cut-off", conv.supply_v.min <= b.cutoff_v <= bat.output_v.max,
                      f"cut-off at {b.cutoff_v:g} V (parts.{part_of_kind(rig, 'battery')}.cutoff_v), inside the "
                      f"converter's input {conv.supply_v.min:g}-{conv.supply_v.max:g} V"))
    return out


def converter_fuse_check(rig, counts: Mapping[str, int]) -> Result:
    """The fuse ahead of the converter against what the converter's datasheet asks of its input fuse: no
    larger than ``dims.input_fuse_max_a`` (the largest slow-blow fuse it recommends). No datasheet read gives
    the converter's inrush (its peak or I^2t), so the fuse's time-delay class is not checked here: the line
    says so. A converter that gives no limit passes with a line saying its fuse was not checked against it."""
    b, cv_id, fu_id = budget(rig, counts), part_of_kind(rig, "converter"), part_of_kind(rig, "fuse")
    fuse = rig.part(fu_id)
    fa = fuse.rating_a.value if fuse.rating_a is not None else b.fuse_a
    limit = rig.part(cv_id).dims.get("input_fuse_max_a")
    if limit is None:
        return Result("converter input fuse", True, f"converter {cv_id} gives no input fuse limit "
                      f"(parts.{cv_id}.dims.input_fuse_max_a): fuse {fu_id} {fa:g} A not checked against it")
    ok = fa <= limit.value
    return Result("converter input fuse", ok, f"fuse {fu_id} {fa:g} A {'within' if ok else 'ABOVE'} the "
                  f"{limit.value:g} A slow-blow fuse converter {cv_id} allows at most ({limit.source}, "
                  f"{limit.confidence.value}); no inrush figure read: fit a slow-blow (time-delay) fuse")


def sync_check(rig) -> Result:
    """The capture card's trigger level (sync.level_v) inside the Boson's external-sync input range."""
    s, boson_id = rig.desc.sync, rig.desc.sensors.thermal.part
    r = rig.part(boson_id).sync_input_v
    if r is None:
        return Result("sync level", False, f"sync level {s.level_v:g} V (sync.level_v): parts.{boson_id}.sync_input_v "
                                           "is not given, so it cannot be checked against the Boson's external-sync input")
    lo, hi = r.min.value, r.max.value
    ok = lo <= s.level_v <= hi
    return Result("sync level", ok, f"sync level {s.level_v:g} V (sync.level_v) {'within' if ok else 'OUTSIDE'} the "
                                    f"Boson's external-sync input range {lo:g}-{hi:g} V ({r.min.source}, "
                                    f"{r.min.confidence.value})")


def led_check(rig) -> Result:
    """The record button's LED driven straight from a GPIO: its voltage must include the header's 3.3 V."""
    pid = part_of_kind(rig, "button")
    r = rig.part(pid).supply_v
    ok = r is not None and r.min <= GPIO_V <= r.max
    rng = f"{r.min:g}-{r.max:g} V" if r is not None else "(supply_v not given)"
    return Result("button LED voltage", ok, f"LED of {pid} {rng} {'takes' if ok else 'does NOT take'} the "
                                            f"{GPIO_V:g} V GPIO")


def led_current_check(rig) -> Result:
    """The record button's LED current, (3.3 V - its forward voltage) / its series resistor
    (``parts.<button>.dims.led_forward_v``, ``led_series_resistor_ohm``), against what the header pin may
    source (:data:`GPIO_SOURCE_MAX_MA`), or, when the LED is switched by a transistor whose gate the pin
    drives, against that driver's rating (``dims.led_driver_max_ma``). A button that gives neither figure
    passes with a line saying its current was not checked (as the converter's fuse limit)."""
    pid = part_of_kind(rig, "button")
    dims = rig.part(pid).dims
    pin = rig.desc.recording.button.led_pin
    vf, r = dims.get("led_forward_v"), dims.get("led_series_resistor_ohm")
    limit = f"the header pin may source {GPIO_SOURCE_MAX_MA:.3f} mA ({GPIO_SOURCE_SOURCE})"
    if vf is None or r is None:
        return Result("button LED current", True, f"LED current of {pid} NOT checked: parts.{pid}.dims.led_forward_v and "
                      f"led_series_resistor_ohm not given; {limit}, so an LED lit straight from GPIO pin {pin} needs a "
                      "transistor driver")
    ma = max(GPIO_V - vf.value, 0.0) / r.value * 1000.0
    how = f"{ma:.2f} mA (({GPIO_V:g} V - {vf.value:g} V) / {r.value:g} ohm, parts.{pid}.dims)"
    drv = dims.get("led_driver_max_ma")
    if drv is not None:
        ok = ma <= drv.value
        return Result("button LED current", ok, f"LED of {pid} draws {how} through its transistor driver rated "
                      f"{drv.value:g} mA (parts.{pid}.dims.led_driver_max_ma)" + ("" if ok else ": OVER its rating")
                      + f"; GPIO pin {pin} drives only the driver's gate")
    if ma <= GPIO_SOURCE_MAX_MA:
        return Result("button LED current", True, f"LED of {pid} draws {how} from GPIO pin {pin}: within what {limit}")
    return Result("button LED current", False, f"LED of {pid} draws {how} from GPIO pin {pin}, more than {limit}: "
                  f"switch it with a transistor (an N-MOSFET low-side switch, its gate on pin {pin}) and give its "
                  f"rating as parts.{pid}.dims.led_driver_max_ma")


def cutoff_check(rig, counts: Mapping[str, int]) -> Result:
    """The under-voltage cut-off: switching the fused current at up to the pack's full voltage, and
    powered across the pack's whole range down to the cut-off it must act at."""
    b = budget(rig, counts)
    pid = part_of_kind(rig, "cutoff")
    part = rig.part(pid)
    a, v, miss = _rated(part, pid, "cut-off")
    if miss:
        return Result("cut-off rating", False, miss)
    rng = part.supply_v
    ok = a >= b.fuse_a and v >= b.max_v and rng is not None and rng.min <= b.cutoff_v and b.max_v <= rng.max
    span = f"{rng.min:g}-{rng.max:g} V" if rng is not None else "(supply_v not given)"
    return Result("cut-off rating", ok, f"cut-off {pid} rated {a:g} A at {v:g} V DC, working {span}: "
                  + ("covers" if ok else "does NOT cover") + f" the fuse's {b.fuse_a:g} A and the pack's "
                  f"{b.cutoff_v:g}-{b.max_v:g} V")


def gland_check(rig) -> Result:
    """The cable gland's seal grips the battery lead, and its hole is no smaller than its thread."""
    pid = part_of_kind(rig, "gland")
    d = lambda k: rig.dim(pid, k)
    cable, lo, hi = d("cable_diameter_mm"), d("clamp_min_mm"), d("clamp_max_mm")
    hole, thread = d("hole_diameter_mm"), d("thread_diameter_mm")
    ok = lo <= cable <= hi and hole >= thread
    return Result("cable gland", ok, f"gland {pid} clamps {lo:g}-{hi:g} mm: the {cable:g} mm battery lead "
                  f"(parts.{pid}.dims.cable_diameter_mm) {'is' if lo <= cable <= hi else 'is NOT'} gripped; hole "
                  f"{hole:g} mm for its {thread:g} mm thread" + ("" if hole >= thread else " (too small)"))


def electrical_checks(rig, counts: Mapping[str, int]) -> list[Result]:
    return power_checks(rig, counts) + [converter_fuse_check(rig, counts), cutoff_check(rig, counts), gland_check(rig),
                                        sync_check(rig), led_check(rig), led_current_check(rig)]
