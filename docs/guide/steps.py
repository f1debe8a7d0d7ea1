"""The assembly guide: docs/assembly/steps.yaml checked against the CAD assembly and the BOM.

Each step adds assembly nodes (by name, or a shell pattern such as ``screw_handle_*`` so that a rig
change that adds screws adds them to the right step), non-CAD supplies (catalogue ids), tools and
notes. Notes, titles and tools are jinja2 templates rendered with the rig (``sync``, ``button``,
``printer``, ``insert``, ``insert_temperature_c`` ...): no number the rig holds is written in the file.

:func:`load_guide` raises :class:`GuideError` (one line per problem, naming steps.yaml, the line and the
entry) when a step names a node the assembly does not have, a node is added twice or by no step, a
supply is unknown, or a BOM line is used by no step.

The power chain's order is not written in the file either: notes say ``{{ chain.wire }}`` (the whole
chain, battery to converter, in the wiring diagram's order, the parts a later step fits left open for
it) and ``{{ chain.join }}`` (in the step that fits a part left open: what to connect it between);
:func:`power_chain` reads the chain from docs/guide/wiring.py's power wires.
"""
from __future__ import annotations

import fnmatch
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Literal, Mapping, Optional

import jinja2

from platform_tools.rig.typed import Gt, closest, convert
from platform_tools.rig.problems import InputProblems
from platform_tools.rig.yamlsource import load_typed

from cad.bought.base import part_of_kind
from bom.bom import Bom, Line

DEFAULT_STEPS = Path(__file__).resolve().parents[1] / "assembly" / "steps.yaml"


class GuideError(InputProblems):
    """docs/assembly/steps.yaml is not valid for this assembly: one line per problem."""


@dataclass(frozen=True)
class StepSpec:
    id: str
    title: str
    nodes: tuple[str, ...] = ()
    supplies: tuple[str, ...] = ()
    tools: tuple[str, ...] = ()
    notes: tuple[str, ...] = ()
    #: direction from the model towards the camera of the step's picture (rig frame)
    view: Optional[tuple[float, float, float]] = None
    #: cable routes (cad/cables.py names, or shell patterns) this step lays: drawn in its cable picture
    cables: tuple[str, ...] = ()
    #: a sub-assembly put together on the bench, off the rig: the assembly-order check drives its screws
    #: clear of the step's own parts only (cad/assembly_order.py)
    bench: bool = False


@dataclass(frozen=True)
class GuideSpec:
    schema_version: Literal[1]
    #: soldering iron temperature for heat-set inserts, per printing material (printing.printer.material)
    insert_temperature_c: Mapping[str, Annotated[float, Gt(0)]]
    #: the tool each fastener needs, by its part id
    fastener_tools: Mapping[str, str]
    steps: tuple[StepSpec, ...]
    #: minutes per operation (insert, screw, part, supply), the time estimate of every step
    operation_minutes: Mapping[Literal["insert", "screw", "part", "supply"], Annotated[float, Gt(0)]]
    #: where those minutes come from
    operation_basis: str


@dataclass
class Item:
    line: Line
    count: int
    nodes: list[str]
    hosts: list[str] = field(default_factory=list)


@dataclass
class Step:
    number: int
    id: str
    title: str
    nodes: list[str]                 # added by this step, in assembly order
    parts: list[Item]
    fasteners: list[Item]
    supplies: list[Item]
    tools: list[str]
    notes: list[str]
    view: tuple[float, float, float]
    picture: str = ""                # relative path, set by the site writer
    closeup: str = ""                # the close-up framed on the step's new parts (set by the site writer)
    callouts: list = field(default_factory=list)   # fastener labels of the close-up (docs.guide.pictures.callouts)
    cables: list = field(default_factory=list)     # the cable routes this step lays (cad.cables.cable_lengths rows)
    cable_picture: str = ""          # the cables drawn in the assembled rig (set by the site writer)
    minutes: float = 0.0             # the time estimate (operation_minutes x the operations counted)
    operations: dict = field(default_factory=dict)   # operation -> count

    @property
    def time_text(self) -> str:
        plural = lambda op: "supplies" if op == "supply" else op + "s"
        return ", ".join(f"{n} {op if n == 1 else plural(op)}" for op, n in self.operations.items() if n)


@dataclass
class Guide:
    path: Path
    steps: list[Step]
    insert_temperature_c: float
    operation_minutes: dict = field(default_factory=dict)
    operation_basis: str = ""

    @property
    def minutes(self) -> float:
        return sum(s.minutes for s in self.steps)


DEFAULT_VIEW = (1.0, 0.75, 0.9)

#: wiring-diagram blocks of the power chain whose part kind is not the block's id: the battery's + is the
#: dock adapter's terminal (the battery itself slides in at the last step)
CHAIN_KIND = {"battery": "battery_adapter"}
#: how the guide's text names each block of the power chain
CHAIN_NAME = {"battery": "battery + (the dock adapter's + terminal)", "gland": "cable gland", "fuse": "fuse",
              "switch": "power switch", "cutoff": "under-voltage cut-off", "converter": "converter input"}


@dataclass(frozen=True)
class ChainPart:
    block: str                 # the block of docs/guide/wiring.py
    name: str                  # as the guide names it
    nodes: tuple[str, ...]     # the assembly nodes of its part


def power_chain(asm) -> list[ChainPart]:
    """The power chain in the wiring diagram's order: its power wires followed from the battery to the
    converter's input (the converter's output is the Orin's DC lead, another circuit)."""
    from cad.electrical import power_counts
    from docs.guide.wiring import wiring
    rig = asm.rig
    _, wires, _ = wiring(rig, power_counts(asm))
    onward: dict[str, str] = {}
    for w in wires:
        if w.kind == "power":
            onward.setdefault(w.a, w.b)
    out: list[ChainPart] = []
    block: str | None = "battery"
    while block is not None and block not in [c.block for c in out]:
        pid = part_of_kind(rig, CHAIN_KIND.get(block, block))
        out.append(ChainPart(block, CHAIN_NAME.get(block, block),
                             tuple(n.name for n in asm.nodes if n.part_id == pid)))
        if rig.part(pid).kind.value == "converter":
            break
        block = onward.get(block)
    return out


class ChainText:
    """The power chain as one step's notes say it: ``wire`` and ``join`` (module docstring)."""

    def __init__(self, chain: list[ChainPart], fitted_in: Mapping[str, int], step: int):
        self.chain, self.step = chain, step
        #: the step (0-based) that fits each part of the chain (its first node)
        self.at = [min((fitted_in[n] for n in c.nodes if n in fitted_in), default=-1) for c in chain]

    def _neighbours(self, k: int) -> tuple[str, str]:
        before = next((self.chain[j].name for j in range(k - 1, -1, -1) if self.at[j] <= self.step), "")
        after = next((self.chain[j].name for j in range(k + 1, len(self.chain)) if self.at[j] <= self.step), "")
        return before, after

    @property
    def wire(self) -> str:
        out = []
        for k, c in enumerate(self.chain):
            if self.at[k] <= self.step:
                out.append(c.name)
                continue
            before, after = self._neighbours(k)
            leads = " and ".join(x for x in (f"a lead from the {before}" if before else "",
                                             f"{'one' if before else 'a lead'} to the {after}" if after else "") if x)
            out.append(f"[{c.name}: fitted in step {self.at[k] + 1}, leave {leads} free for it]")
        return " -> ".join(out)

    @property
    def join(self) -> str:
        left = [k for k, c in enumerate(self.chain) if self.at[k] == self.step
                and any(self.at[j] < self.step for j in range(len(self.chain)))]
        if not left:
            raise jinja2.TemplateRuntimeError("chain.join: this step fits no part of the power chain after an "
                                              "earlier step wired the rest")
        texts = []
        for k in left:
            before, after = self._neighbours(k)
            texts.append(f"connect the {self.chain[k].name} between the {before} and the {after}"
                         if before and after else f"connect the {self.chain[k].name} to the {before or after}")
        return "; ".join(texts)


def note_context(rig) -> dict:
    d = rig.desc
    return dict(rig=d, sync=d.sync, button=d.recording.button, printer=d.printing.printer,
                insert=rig.part(d.enclosure.insert), screw=rig.part(d.enclosure.screw), heat_sink=d.enclosure.heat_sink,
                sync_source=rig.part(d.sync.source_part), thermal=d.sensors.thermal,
                battery=rig.part(part_of_kind(rig, "battery")))


def load_guide(asm, bom: Bom, path: Path | str | None = None) -> Guide:
    path = Path(path) if path is not None else DEFAULT_STEPS
    typed = load_typed(path, GuideSpec, GuideError)
    spec, src = typed.value, typed.source
    out: list[str] = []

    def bad(key: tuple, message: str) -> None:
        from platform_tools.rig.typed import format_path
        out.append(f"{src.where(key)}: {format_path(key)}: {message}")

    rig = asm.rig
    material = rig.desc.printing.printer.material
    if material not in spec.insert_temperature_c:
        bad(("insert_temperature_c",), f"has no temperature for {material} (printing.printer.material); "
                                       f"add {material}: <degrees C>")
    ctx = note_context(rig)
    ctx["insert_temperature_c"] = spec.insert_temperature_c.get(material, 0)
    env = jinja2.Environment(undefined=jinja2.StrictUndefined, autoescape=False,
                             finalize=lambda v: f"{v:g}" if isinstance(v, float) else v)

    def render(text: str, key: tuple) -> str:
        try:
            return env.from_string(text).render(ctx)
        except jinja2.TemplateError as exc:
            bad(key, f"{text!r}: {exc}")
            return text

    names = [n.name for n in asm.nodes]
    node_by_name = {n.name: n for n in asm.nodes}
    fitted_in: dict[str, int] = {}      # node -> the (first) step that adds it, for the chain's text
    for i, s in enumerate(spec.steps):
        for pat in s.nodes:
            for m in fnmatch.filter(names, pat):
                fitted_in.setdefault(m, i)
    chain = power_chain(asm)
    cables = bom.cables
    claimed: dict[str, str] = {}
    seen_ids: dict[str, int] = {}
    line_of = bom.line_of_node()
    lines = {ln.key: ln for ln in bom.lines}
    supply_used: set[str] = set()
    steps: list[Step] = []
    for i, s in enumerate(spec.steps):
        key = ("steps", i)
        ctx["chain"] = ChainText(chain, fitted_in, i)
        if s.id in seen_ids:
            bad(key + ("id",), f"{s.id!r} is already the id of steps[{seen_ids[s.id]}]")
        seen_ids[s.id] = i
        added: list[str] = []
        for j, pat in enumerate(s.nodes):
            matches = fnmatch.filter(names, pat)
            if not matches:
                hint = closest(pat, names)
                bad(key + ("nodes", j), f"{pat!r} is not a node of the CAD assembly"
                    + (f" (did you mean {hint!r}?)" if hint else "") + " (step " + repr(s.id) + ")")
                continue
            new = [m for m in matches if m not in claimed]
            if not new:
                bad(key + ("nodes", j), f"{pat!r} adds nothing: step {claimed[matches[0]]!r} already adds "
                                        + ", ".join(matches[:3]))
            for m in new:
                claimed[m] = s.id
                added.append(m)
        for j, sid in enumerate(s.supplies):
            ln = lines.get(sid)
            if ln is None or ln.source == "CAD assembly":
                why = "is placed by the CAD model: add its nodes instead" if ln is not None else \
                    "is not a supply of the catalogue (in_cad: false)"
                hint = closest(sid, [x.key for x in bom.lines if x.source != "CAD assembly"])
                bad(key + ("supplies", j), f"{sid!r} {why}" + (f" (did you mean {hint!r}?)" if hint and ln is None else ""))
                continue
            supply_used.add(sid)
        order = {n: k for k, n in enumerate(names)}
        added.sort(key=order.__getitem__)
        parts: dict[str, Item] = {}
        fasteners: dict[str, Item] = {}
        for name in added:
            n = node_by_name[name]
            lk = line_of.get(name)
            if lk is None:
                continue
            bucket = fasteners if n.category == "fastener" else parts
            it = bucket.setdefault(lk, Item(lines[lk], 0, []))
            it.count += 1
            it.nodes.append(name)
            host = n.props.get("host")
            if host and host not in it.hosts:
                it.hosts.append(host)
        tools = [render(t, key + ("tools", j)) for j, t in enumerate(s.tools)]
        for it in fasteners.values():
            pid = it.line.entry_id
            if pid not in spec.fastener_tools:
                bad(("fastener_tools",), f"has no tool for {pid} (used in step {s.id!r}); add {pid}: <tool>")
                continue
            tool = render(spec.fastener_tools[pid], ("fastener_tools", pid))
            if tool not in tools:
                tools.append(tool)
        supplies = [Item(lines[x], 0, []) for x in s.supplies if x in lines and x in supply_used]
        laid = []
        for j, pat in enumerate(s.cables):
            found = [c for c in cables if fnmatch.fnmatch(c["route"], pat)]
            if not found:
                hint = closest(pat, [c["route"] for c in cables])
                bad(key + ("cables", j), f"{pat!r} is not a cable route of cad/cables.py"
                    + (f" (did you mean {hint!r}?)" if hint else ""))
            laid += [c for c in found if c not in laid]
        ops = operation_counts(rig, list(parts.values()), list(fasteners.values()), supplies)
        steps.append(Step(i + 1, s.id, render(s.title, key + ("title",)), added, list(parts.values()),
                          list(fasteners.values()), supplies,
                          tools, [render(t, key + ("notes", j)) for j, t in enumerate(s.notes)],
                          tuple(s.view) if s.view else DEFAULT_VIEW,
                          minutes=sum(n * spec.operation_minutes[op] for op, n in ops.items()), operations=ops,
                          cables=laid))
    missing = [n for n in names if n not in claimed]
    if missing:
        out.append(f"{path}: steps: no step adds {len(missing)} node(s) of the CAD assembly: "
                   + ", ".join(missing[:8]) + (" ..." if len(missing) > 8 else "") + "; add them to a step's nodes")
    for ln in bom.lines:
        used = any(n in claimed for n in ln.nodes) if ln.source == "CAD assembly" else ln.key in supply_used
        if not used:
            out.append(f"{path}: steps: BOM line {ln.key!r} ({ln.name}) is used by no step; "
                       + ("add its nodes to a step" if ln.nodes else "add it to a step's supplies"))
    if out:
        raise GuideError(out)
    return Guide(path, steps, spec.insert_temperature_c[material], dict(spec.operation_minutes), spec.operation_basis)


def operation_counts(rig, parts: list[Item], fasteners: list[Item], supplies: list[Item]) -> dict[str, int]:
    """What a step does, counted from its items: inserts set, screws driven, parts fitted, supplies used."""
    insert = rig.desc.enclosure.insert
    return dict(insert=sum(it.count for it in fasteners if it.line.entry_id == insert),
                screw=sum(it.count for it in fasteners if it.line.entry_id != insert),
                part=sum(it.count for it in parts), supply=len(supplies))
