"""The assembly guide: docs/assembly/steps.yaml checked against the CAD assembly and the BOM.

Each step adds assembly nodes (by name, or a shell pattern such as ``screw_handle_*`` so that a rig
change that adds screws adds them to the right step), non-CAD supplies (catalogue ids), tools and
notes. Notes, titles and tools are jinja2 templates rendered with the rig (``sync``, ``button``,
``printer``, ``insert``, ``insert_temperature_c`` ...): no number the rig holds is written in the file.

:func:`load_guide` raises :class:`GuideError` (one line per problem, naming steps.yaml, the line and the
entry) when a step names a node the assembly does not have, a node is added twice or by no step, a
supply is unknown, or a BOM line is used by no step.
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


@dataclass(frozen=True)
class GuideSpec:
    schema_version: Literal[1]
    #: soldering iron temperature for heat-set inserts, per printing material (printing.printer.material)
    insert_temperature_c: Mapping[str, Annotated[float, Gt(0)]]
    #: the tool each fastener needs, by its part id
    fastener_tools: Mapping[str, str]
    steps: tuple[StepSpec, ...]


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


@dataclass
class Guide:
    path: Path
    steps: list[Step]
    insert_temperature_c: float


DEFAULT_VIEW = (1.0, 0.75, 0.9)


def note_context(rig) -> dict:
    d = rig.desc
    return dict(rig=d, sync=d.sync, button=d.recording.button, printer=d.printing.printer,
                insert=rig.part(d.enclosure.insert), screw=rig.part(d.enclosure.screw), heat_sink=d.enclosure.heat_sink,
                sync_source=rig.part(d.sync.source_part), thermal=d.sensors.thermal)


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
    claimed: dict[str, str] = {}
    seen_ids: dict[str, int] = {}
    line_of = bom.line_of_node()
    lines = {ln.key: ln for ln in bom.lines}
    supply_used: set[str] = set()
    steps: list[Step] = []
    for i, s in enumerate(spec.steps):
        key = ("steps", i)
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
        steps.append(Step(i + 1, s.id, render(s.title, key + ("title",)), added, list(parts.values()),
                          list(fasteners.values()),
                          [Item(lines[x], 0, []) for x in s.supplies if x in lines and x in supply_used],
                          tools, [render(t, key + ("notes", j)) for j, t in enumerate(s.notes)],
                          tuple(s.view) if s.view else DEFAULT_VIEW))
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
    return Guide(path, steps, spec.insert_temperature_c[material])
