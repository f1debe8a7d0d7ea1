"""The wiring diagram: an SVG drawn from the rig description (parts, voltages, sync pins, GPIO pins).

Blocks stand where their role puts them (power chain on the left, the Orin and capture card in the
middle, cameras and fans on the right, controls below); every label that is a rig value (voltages,
connector and pin numbers, the trigger level and edge, GPIO pins) is read from the rig, and the
electrical checks below are computed from the same values.
"""
from __future__ import annotations

from dataclasses import dataclass
from html import escape

from cad.bought.base import part_of_kind
from cad.cable_leads import HEADER_5V_PIN, HEADER_GND_PIN   # the fans' pins of the Jetson 40-pin header
from cad.electrical import budget, electrical_checks

KINDS = {  # colour, label
    "power": ("#d62728", "power"),
    "data": ("#1f5fbf", "data"),
    "sync": ("#2ca02c", "sync trigger"),
    "gpio": ("#8e44ad", "GPIO"),
    "ground": ("#333333", "ground"),
}


@dataclass
class Block:
    id: str
    x: float
    y: float
    w: float
    h: float
    title: str
    lines: list[str]


@dataclass
class Wire:
    kind: str
    a: str
    b: str
    label: str
    path: list[tuple[float, float]]
    label_at: tuple[float, float] | None = None   # start of the label (left aligned); default: mid first segment


@dataclass
class Check:
    ok: bool
    text: str


def _v(r) -> str:
    return f"{r.min:g} V" if r.min == r.max else f"{r.min:g}-{r.max:g} V"


def _named(part) -> str:
    """The part as the rig description names it: the maker's first word and the part number ("generic" for a
    part not chosen yet)."""
    return "generic" if part.vendor.lower() == "generic" else f"{part.vendor.split()[0]} {part.part_number}"


def _rating(part) -> str:
    """A switch's DC rating, from the rig (``rating_a`` at ``rating_dc_v``)."""
    a, v = part.rating_a, part.rating_dc_v
    return f"{a.value:g} A at {v.value:g} V DC" if a and v else "DC rating not given"


def wiring(rig, counts) -> tuple[list[Block], list[Wire], list[Check]]:
    """Blocks, wires and electrical checks; ``counts`` (part id -> how many, cad.electrical.power_counts)
    gives the power budget the switch and fuse are checked against."""
    d = rig.desc
    P = rig.part
    s, b = d.sync, d.recording.button
    def K(kind: str):   # the rig's part of that kind
        return P(part_of_kind(rig, kind))

    bat, conv, orin, fan = K("battery"), K("converter"), K("computer"), K("fan")
    src, boson = P(s.source_part), P(d.sensors.thermal.part)
    bud = budget(rig, counts)
    fuse, switch = K("fuse"), K("switch")
    sync_in = boson.sync_input_v
    sync_rng = f"{sync_in.min.value:g}-{sync_in.max.value:g} V" if sync_in is not None else "range not given"
    blocks = [
        Block("battery", 30, 30, 230, 54, bat.vendor + " " + bat.part_number + " on " + K("battery_adapter").part_number,
              [f"out {_v(bat.output_v)}, cut-off {bud.cutoff_v:g} V"]),
        Block("gland", 30, 110, 230, 40, "cable gland, strain relief (floor)", []),
        Block("fuse", 30, 175, 230, 54, f"fuse {fuse.rating_a.value if fuse.rating_a else '?'} A", [fuse.part_number]),
        Block("switch", 30, 255, 230, 54, f"power switch, {_rating(switch)}", [_named(switch)]),
        Block("cutoff", 30, 335, 230, 40, f"under-voltage cut-off at {bud.cutoff_v:g} V", []),
        Block("converter", 30, 400, 230, 54, f"DC-DC converter {_v(conv.supply_v)} to {_v(conv.output_v)}",
              [_named(conv) + (f", {conv.efficiency.value:.0%} eff." if conv.efficiency is not None else "")]),
        Block("card", 370, 40, 300, 90, f"{src.part_number} (capture card)",
              ["GMSL2 camera ports", f"{s.connector}: trigger out, pin {s.signal_pin} signal, pin {s.ground_pin} GND"]),
        Block("orin", 370, 200, 300, 290, "Jetson AGX Orin devkit",
              [f"DC jack, in {_v(orin.supply_v)}", "USB ports", "M.2: NVMe SSD, Wi-Fi card",
               f"40-pin header ({b.pin_numbering} numbering):",
               f"  pin {b.gpio_pin} record button",
               f"  pin {b.led_pin} button LED",
               f"  pin {HEADER_5V_PIN} 5 V, pin {HEADER_GND_PIN} GND (fans)"]),
        Block("zed", 790, 40, 230, 70, "ZED X", ["GMSL2 (Fakra)"]),
        Block("boson_left", 790, 170, 230, 70, "Boson 640 left", ["USB-C; interface board", f"EXT_SYNC in {sync_rng}"]),
        Block("boson_right", 790, 290, 230, 70, "Boson 640 right", ["USB-C; interface board", f"EXT_SYNC in {sync_rng}"]),
        Block("fans", 790, 410, 230, 70, f"2 x {fan.part_number}", [f"{_v(fan.supply_v)}"]),
        Block("button", 370, 560, 300, 70, "record button with LED", [K("button").part_number]),
        Block("wifi", 30, 540, 230, 60, "2 x Wi-Fi antenna", ["RP-SMA bulkheads, u.fl pigtails"]),
        Block("ssd", 30, 640, 230, 50, "NVMe SSD", ["recordings (" + d.recording.data_mount + ")"]),
    ]
    wires = [
        Wire("power", "battery", "gland", f"+ {_v(bat.output_v)}, {bud.battery_a:.1f} A max", [(145, 84), (145, 110)]),
        Wire("power", "gland", "fuse", "", [(145, 150), (145, 175)]),
        Wire("power", "fuse", "switch", "fused +", [(145, 229), (145, 255)]),
        Wire("power", "switch", "cutoff", "switched +", [(145, 309), (145, 335)]),
        Wire("power", "cutoff", "converter", "", [(145, 375), (145, 400)]),
        Wire("power", "converter", "orin", f"{_v(conv.output_v)} to DC jack", [(260, 427), (315, 427), (315, 230), (370, 230)],
             label_at=(266, 470)),
        Wire("ground", "battery", "converter", "battery - (common ground)", [(30, 70), (15, 70), (15, 440), (30, 440)],
             label_at=(20, 490)),
        Wire("power", "orin", "fans", f"5 V pin {HEADER_5V_PIN} / GND pin {HEADER_GND_PIN}", [(670, 445), (790, 445)]),
        Wire("data", "zed", "card", "GMSL2", [(790, 75), (670, 75)]),
        Wire("data", "card", "orin", "camera connector", [(520, 130), (520, 200)]),
        Wire("data", "boson_left", "orin", "USB", [(790, 215), (730, 215), (730, 260), (670, 260)]),
        Wire("data", "boson_right", "orin", "USB", [(790, 335), (730, 335), (730, 290), (670, 290)]),
        Wire("sync", "card", "boson_left", f"{s.connector}.{s.signal_pin}: {s.level_v:g} V, {s.edge} edge, {s.rate_hz:g} Hz",
             [(670, 115), (760, 115), (760, 195), (790, 195)], label_at=(768, 138)),
        Wire("sync", "card", "boson_right", "", [(760, 195), (760, 315), (790, 315)]),
        Wire("ground", "card", "boson_left", f"{s.connector}.{s.ground_pin} GND", [(670, 125), (750, 125), (750, 230), (790, 230)], label_at=(768, 156)),
        Wire("ground", "card", "boson_right", "", [(750, 230), (750, 350), (790, 350)]),
        Wire("gpio", "button", "orin", f"pin {b.gpio_pin} (button), pin {b.led_pin} (LED)", [(520, 560), (520, 490)]),
        Wire("data", "wifi", "orin", "u.fl", [(260, 570), (340, 570), (340, 470), (370, 470)]),
        Wire("data", "ssd", "orin", "M.2", [(260, 665), (350, 665), (350, 480), (370, 480)]),
    ]
    checks = [Check(r.ok, r.text) for r in electrical_checks(rig, counts)] + [
        Check(bat.output_v.max <= conv.supply_v.max and bat.output_v.min >= conv.supply_v.min,
              f"battery {_v(bat.output_v)} within the converter's input {_v(conv.supply_v)}"),
        Check(orin.supply_v.min <= conv.output_v.min and conv.output_v.max <= orin.supply_v.max,
              f"converter output {_v(conv.output_v)} within the Orin's input {_v(orin.supply_v)}"),
        Check(fan.supply_v.min <= 5.0 <= fan.supply_v.max, f"fans ({_v(fan.supply_v)}) on the header's 5 V"),
        Check(len({b.gpio_pin, b.led_pin, HEADER_5V_PIN, HEADER_GND_PIN}) == 4,
              f"header pins distinct: button {b.gpio_pin}, LED {b.led_pin}, fan 5 V {HEADER_5V_PIN}, GND {HEADER_GND_PIN}"),
    ]
    return blocks, wires, checks


def _fit(text: str, width: float, px_per_char: float = 6.3) -> str:
    n = int(width / px_per_char)
    return text if len(text) <= n else text[:n - 1].rstrip(" ,") + "…"


def svg(rig, counts) -> str:
    blocks, wires, _ = wiring(rig, counts)
    W, H = 1050, 760
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" viewBox="0 0 {W} {H}" '
           'font-family="DejaVu Sans, sans-serif" font-size="12">',
           f'<title>Wiring of {escape(rig.desc.name)}</title>',
           f'<rect width="{W}" height="{H}" fill="#ffffff"/>']
    for w in wires:
        colour = KINDS[w.kind][0]
        pts = " ".join(f"{x:g},{y:g}" for x, y in w.path)
        dash = ' stroke-dasharray="6 4"' if w.kind == "ground" else ""
        out.append(f'<polyline class="wire {w.kind}" data-from="{w.a}" data-to="{w.b}" points="{pts}" fill="none" '
                   f'stroke="{colour}" stroke-width="2.5"{dash}/>')
    for bl in blocks:
        out.append(f'<g class="block" id="blk-{bl.id}"><rect x="{bl.x}" y="{bl.y}" width="{bl.w}" height="{bl.h}" '
                   'rx="6" fill="#f4f6f8" stroke="#24323f" stroke-width="1.5"/>')
        out.append(f'<text x="{bl.x + 10}" y="{bl.y + 20}" font-weight="bold">{escape(bl.title)}</text>')
        for k, line in enumerate(bl.lines):
            out.append(f'<text x="{bl.x + 10}" y="{bl.y + 38 + 16 * k}" xml:space="preserve">'
                       f'{escape(_fit(line, bl.w - 16))}</text>')
        out.append("</g>")
    for w in wires:  # labels on top of blocks' edges
        if not w.label:
            continue
        (x0, y0), (x1, y1) = w.path[0], w.path[1]
        x, y = (x0 + x1) / 2, (y0 + y1) / 2
        vertical = abs(x1 - x0) < 1
        tx, ty = (x + 6, y + 4) if vertical else (x, y - 6)
        anchor = "start" if vertical else "middle"
        if w.label_at is not None:
            (tx, ty), anchor = w.label_at, "start"
        out.append(f'<text x="{tx:g}" y="{ty:g}" text-anchor="{anchor}" fill="{KINDS[w.kind][0]}" font-size="11" '
                   f'paint-order="stroke" stroke="#ffffff" stroke-width="3">{escape(w.label)}</text>')
    y = H - 20
    x = 300
    for kind, (colour, label) in KINDS.items():
        dash = ' stroke-dasharray="6 4"' if kind == "ground" else ""
        out.append(f'<line x1="{x}" y1="{y}" x2="{x + 30}" y2="{y}" stroke="{colour}" stroke-width="3"{dash}/>'
                   f'<text x="{x + 36}" y="{y + 4}">{label}</text>')
        x += 130
    out.append("</svg>")
    return "\n".join(out) + "\n"
