"""Rules that span several keys of the rig description.

Types and ranges of single values are checked while loading (:mod:`platform_tools.rig.typed`);
here are the rules that relate values: references between sections, orderings, physical fits.
Each rule returns :class:`Problem` entries naming the key to change.
"""
from __future__ import annotations

from typing import Callable, Iterable, Iterator

from .model import Rig, _walk_sourced
from .schema import PartKind
from .typed import Problem, closest

Rule = Callable[[Rig], Iterable[Problem]]
RULES: list[Rule] = []


def rule(fn: Rule) -> Rule:
    RULES.append(fn)
    return fn


def check_rules(rig: Rig) -> list[Problem]:
    problems: list[Problem] = []
    for fn in RULES:
        problems.extend(fn(rig))
    return problems


def _ref(rig: Rig, path: tuple, part_id: str, kind: PartKind) -> Iterator[Problem]:
    parts = rig.desc.parts
    if part_id not in parts:
        hint = closest(part_id, parts)
        yield Problem(path, f"names part {part_id!r}, which is not in parts"
                            + (f" (did you mean {hint!r}?)" if hint else ""))
    elif parts[part_id].kind is not kind:
        yield Problem(path, f"names part {part_id!r} of kind {parts[part_id].kind.value}; "
                            f"expected a part of kind {kind.value}")


@rule
def part_references(rig: Rig) -> Iterator[Problem]:
    d = rig.desc
    yield from _ref(rig, ("sensors", "zed_x", "part"), d.sensors.zed_x.part, PartKind.STEREO_CAMERA)
    yield from _ref(rig, ("sensors", "thermal", "part"), d.sensors.thermal.part, PartKind.THERMAL_CAMERA)
    yield from _ref(rig, ("sensors", "thermal", "lens"), d.sensors.thermal.lens, PartKind.LENS)
    yield from _ref(rig, ("enclosure", "screw"), d.enclosure.screw, PartKind.SCREW)
    yield from _ref(rig, ("enclosure", "insert"), d.enclosure.insert, PartKind.INSERT)
    yield from _ref(rig, ("sync", "source_part"), d.sync.source_part, PartKind.CAPTURE_CARD)


@rule
def camera_model_references(rig: Rig) -> Iterator[Problem]:
    models = rig.desc.camera_models
    for path, name in ((("sensors", "zed_x", "camera_model"), rig.desc.sensors.zed_x.camera_model),
                       (("sensors", "thermal", "camera_model"), rig.desc.sensors.thermal.camera_model)):
        if name not in models:
            hint = closest(name, models)
            yield Problem(path, f"names camera model {name!r}, which is not in camera_models"
                                + (f" (did you mean {hint!r}?)" if hint else ""))


@rule
def source_references(rig: Rig) -> Iterator[Problem]:
    sources = rig.desc.sources
    for path, s in _walk_sourced(rig.desc, ()):
        if s.source not in sources:
            hint = closest(s.source, sources)
            yield Problem(path + ("source",), f"names source {s.source!r}, which is not in sources"
                                              + (f" (did you mean {hint!r}?)" if hint else ""))
    for pid, part in rig.desc.parts.items():
        for i, m in enumerate(part.mounting):
            if m.source not in sources:
                yield Problem(("parts", pid, "mounting", i, "source"),
                              f"names source {m.source!r}, which is not in sources")


@rule
def required_dimensions(rig: Rig) -> Iterator[Problem]:
    """Dimensions the derived frames need."""
    zed = rig.desc.sensors.zed_x.part
    if zed in rig.desc.parts:
        for name in ("baseline_mm", "imu_x_mm", "imu_y_mm", "imu_z_mm"):
            if name not in rig.desc.parts[zed].dims:
                yield Problem(("parts", zed, "dims", name), "is missing; the ZED X optical frames and IMU need it")


@rule
def thermal_baseline_fits(rig: Rig) -> Iterator[Problem]:
    t = rig.desc.sensors.thermal
    if t.part not in rig.desc.parts or rig.desc.parts[t.part].kind is not PartKind.THERMAL_CAMERA:
        return
    body = rig.part(t.part).envelope_mm.y.value
    module = rig.thermal_module_width_mm()
    gap = rig.desc.enclosure.heat_sink_gap_mm
    need = module + gap
    if t.baseline_mm < need:
        hs = (module - body) / 2
        yield Problem(("sensors", "thermal", "baseline_mm"),
                      f"got {t.baseline_mm:g} mm; the two Bosons would overlap: one camera with its heat sink is "
                      f"{module:g} mm wide ({body:g} mm body + 2 x {hs:g} mm heat sink) and they need "
                      f"{gap:g} mm between them; expected >= {need:g} mm")


@rule
def thermal_cameras_distinct(rig: Rig) -> Iterator[Problem]:
    left, right = rig.desc.sensors.thermal.left, rig.desc.sensors.thermal.right
    if left.serial is not None and left.serial == right.serial:
        yield Problem(("sensors", "thermal", "right", "serial"),
                      f"is {right.serial}, the same as sensors.thermal.left.serial; "
                      f"expected the serial number of a different camera")
    if left.device_name == right.device_name:
        yield Problem(("sensors", "thermal", "right", "device_name"),
                      f"is {right.device_name!r}, the same as the left camera's; expected a different name")


@rule
def fits_in_order(rig: Rig) -> Iterator[Problem]:
    f = rig.desc.printing.fits
    if not f.press_mm < f.sliding_mm < f.loose_mm:
        yield Problem(("printing", "fits"),
                      f"press {f.press_mm:g} mm, sliding {f.sliding_mm:g} mm, loose {f.loose_mm:g} mm; "
                      f"expected press < sliding < loose")
    for size, h in rig.desc.printing.holes.items():
        if not h.close_mm < h.normal_mm < h.loose_mm:
            yield Problem(("printing", "holes", size),
                          f"close {h.close_mm:g} mm, normal {h.normal_mm:g} mm, loose {h.loose_mm:g} mm; "
                          f"expected close < normal < loose")


@rule
def printable_walls(rig: Rig) -> Iterator[Problem]:
    p = rig.desc.printing.printer
    min_wall = p.nozzle_mm * p.min_wall_nozzles
    if rig.desc.enclosure.wall_mm < min_wall:
        yield Problem(("enclosure", "wall_mm"),
                      f"got {rig.desc.enclosure.wall_mm:g} mm; the printer's thinnest wall is "
                      f"{p.min_wall_nozzles:g} x {p.nozzle_mm:g} mm nozzle = {min_wall:g} mm; expected >= {min_wall:g} mm")
    if p.layer_mm > 0.8 * p.nozzle_mm:
        yield Problem(("printing", "printer", "layer_mm"),
                      f"got {p.layer_mm:g} mm; expected at most 80% of the {p.nozzle_mm:g} mm nozzle "
                      f"({0.8 * p.nozzle_mm:g} mm)")
    if rig.desc.enclosure.vents.slot_width_mm < p.nozzle_mm * 2:
        yield Problem(("enclosure", "vents", "slot_width_mm"),
                      f"got {rig.desc.enclosure.vents.slot_width_mm:g} mm; slots narrower than two nozzle widths "
                      f"({2 * p.nozzle_mm:g} mm) close up when printed")


@rule
def sync_trigger(rig: Rig) -> Iterator[Problem]:
    s = rig.desc.sync
    boson_id = rig.desc.sensors.thermal.part
    boson = rig.desc.parts.get(boson_id)
    top = boson.max_frame_rate_hz if boson is not None else None
    if top is not None and s.rate_hz > top.value:
        yield Problem(("sync", "rate_hz"), f"got {s.rate_hz:g} Hz; the {boson_id} runs at most {top.value:g} Hz "
                                           f"(parts.{boson_id}.max_frame_rate_hz); expected <= {top.value:g}")
    if s.signal_pin == s.ground_pin:
        yield Problem(("sync", "ground_pin"), f"is pin {s.ground_pin}, the same as signal_pin")
    b = rig.desc.recording.button
    if b.gpio_pin == b.led_pin:
        yield Problem(("recording", "button", "led_pin"), f"is pin {b.led_pin}, the same as gpio_pin")


@rule
def power_chain(rig: Rig) -> Iterator[Problem]:
    """Battery -> converter -> computer: each stage's voltage inside the next one's input range."""
    by_kind = {}
    for pid, part in rig.desc.parts.items():
        by_kind.setdefault(part.kind, []).append((pid, part))
    chain = [PartKind.BATTERY, PartKind.CONVERTER, PartKind.COMPUTER]
    stages = [by_kind[k][0] for k in chain if k in by_kind]
    if len(stages) != len(chain):
        return
    for (a_id, a), (b_id, b) in zip(stages, stages[1:]):
        out, inp = a.output_v, b.supply_v
        if out is None:
            yield Problem(("parts", a_id, "output_v"), "is missing; the power chain check needs it")
        elif inp is None:
            yield Problem(("parts", b_id, "supply_v"), "is missing; the power chain check needs it")
        elif out.min < inp.min or out.max > inp.max:
            yield Problem(("parts", b_id, "supply_v"),
                          f"accepts {inp.min:g}-{inp.max:g} V but {a_id} gives {out.min:g}-{out.max:g} V")


@rule
def recording_on_data_drive(rig: Rig) -> Iterator[Problem]:
    r = rig.desc.recording
    mount = r.data_mount.rstrip("/") + "/"
    if not (r.output_dir.rstrip("/") + "/").startswith(mount):
        yield Problem(("recording", "output_dir"),
                      f"is {r.output_dir!r}, not on the data drive {r.data_mount!r}; "
                      f"recordings would fill the eMMC")
    if not r.data_mount.startswith("/"):
        yield Problem(("recording", "data_mount"), f"is {r.data_mount!r}; expected an absolute path")
