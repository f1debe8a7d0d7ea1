"""`check` "assembly order": every screw can be driven at the step that fits it.

The steps are the assembly guide's (``docs/assembly/steps.yaml``): each step names the nodes it adds,
exactly or by shell pattern, and a node belongs to the first step whose pattern matches it (the rule
``docs.guide.steps.load_guide`` applies; a test holds the two to the same answer). At the step that fits
a screw, its driver (the thread's ``driver`` of the fastener table: a bit, then the handle) must have a
straight path along the screw's axis, out from the head, clear of every part installed in that step or
before it (of that step's own parts only, for a step the guide marks ``bench``: a sub-assembly put
together off the rig, such as each Boson in its heat sink with its retaining plate). A failure names the screw, its step and the part in the way.
"""
from __future__ import annotations

import fnmatch
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Sequence

import cadquery as cq
import numpy as np
import yaml

from cad.bought.fasteners import Driver, fastener_table
from cad.solids import TOUCH_MM3, bounds_of, cylinder

from .assembly import Assembly

#: the guide's steps (read as data: cad does not import the guide)
STEPS = Path(__file__).resolve().parents[1] / "docs" / "assembly" / "steps.yaml"
#: the driver's envelope starts this far out from the head's top face, so the bit seated in the socket
#: does not count as touching its own screw's head
SEAT_GAP_MM = 0.05


@dataclass(frozen=True)
class Step:
    """One step of the guide: its id and the assembly nodes it adds, in assembly order; ``bench``: a
    sub-assembly put together off the rig (its screws are driven clear of its own parts only)."""
    number: int
    id: str
    nodes: tuple[str, ...]
    bench: bool = False


def resolve_steps(names: Sequence[str], specs: Iterable[tuple]) -> list[Step]:
    """The nodes each step adds, from ``(id, patterns[, bench])`` in step order: every pattern's matches
    among ``names`` that no earlier step (or pattern) has claimed."""
    claimed: set[str] = set()
    order = {n: k for k, n in enumerate(names)}
    out = []
    for i, (sid, patterns, *rest) in enumerate(specs):
        added = []
        for pat in patterns:
            for m in fnmatch.filter(names, pat):
                if m not in claimed:
                    claimed.add(m)
                    added.append(m)
        out.append(Step(i + 1, sid, tuple(sorted(added, key=order.__getitem__)), bool(rest and rest[0])))
    return out


def load_steps(names: Sequence[str], path: Path | str = STEPS) -> list[Step]:
    """The guide's steps (``steps[].id`` and ``steps[].nodes``) resolved against the assembly's node names."""
    doc = yaml.safe_load(Path(path).read_text())
    return resolve_steps(names, [(s["id"], s.get("nodes") or (), bool(s.get("bench"))) for s in doc["steps"]])


def driver_envelope(asm: Assembly, joint_name: str, driver: Driver | None = None) -> tuple[cq.Shape, np.ndarray, np.ndarray]:
    """The solid a screw's driver sweeps (rig frame), with the head's top centre and the outward axis."""
    j = next(x for x in asm.layout.joints if x.name == joint_name)
    driver = driver or fastener_table().size(j.thread).driver
    out = -np.asarray(j.direction, dtype=float)
    top = np.asarray(j.head, dtype=float) + j.screw.head_height_mm * out
    start = top + SEAT_GAP_MM * out
    bit = cylinder(driver.bit_diameter_mm, driver.bit_length_mm, tuple(start), tuple(out))
    handle = cylinder(driver.handle_diameter_mm, driver.handle_length_mm,
                      tuple(start + driver.bit_length_mm * out), tuple(out))
    return bit.fuse(handle).clean(), top, out


@dataclass(frozen=True)
class OrderReport:
    screws: int
    problems: list[str]      # one line per blocked driver path (screw, step, part in the way)
    details: list[str]
    data: dict               # per screw: its step and what blocks it


def driver_paths(asm: Assembly, steps: list[Step] | None = None,
                 extra: Sequence[tuple[str, cq.Shape]] = ()) -> OrderReport:
    """Each screw's driver path, at its step, against every part installed by then; ``extra`` shapes
    (name, solid in the rig frame) count as installed from the first step on."""
    names = [n.name for n in asm.nodes]
    steps = load_steps(names) if steps is None else steps
    step_of = {n: st for st in steps for n in st.nodes}
    joints = {f"screw_{j.name}": j for j in asm.layout.joints}
    shapes = {n.name: n.shape(asm.cache) for n in asm.nodes}
    boxes = {k: bounds_of(s) for k, s in shapes.items()}
    for name, s in extra:
        shapes[name], boxes[name] = s, bounds_of(s)
    bad, details, data = [], [], {}
    unplaced = [s for s in joints if s not in step_of]
    for screw, j in joints.items():
        st = step_of.get(screw)
        if st is None:
            continue
        # on the bench only the sub-assembly's own parts are in the way; in the rig, everything fitted so far
        installed = [n for s in steps if (s is st if st.bench else s.number <= st.number) for n in s.nodes
                     if n != screw]
        installed += [name for name, _ in extra]
        env, top, out = driver_envelope(asm, j.name)
        env_box = bounds_of(env)
        hits = []
        for other in installed:
            if not env_box.overlaps(boxes[other], 1e-6):
                continue
            common = env.intersect(shapes[other])
            v = common.Volume() if common.Solids() else 0.0
            if v > TOUCH_MM3:
                along = min(float((np.array(p.toTuple()) - top) @ out) for p in common.Vertices())
                where = next((s for s in steps if other in s.nodes), None)
                hits.append((along, other, v, where))
        hits.sort()
        data[screw] = dict(step=st.id, blocked_by=[h[1] for h in hits])
        for along, other, v, where in hits:
            when = f"step {where.number} '{where.id}'" if where else "placed by the test"
            bad.append(f"{screw} (step {st.number} '{st.id}'): its driver is blocked by {other} ({when}) "
                       f"{along:.1f} mm out from the screw head ({v:.1f} mm^3 overlap)")
    bad += [f"{s}: no step of {STEPS.name} fits it" for s in unplaced]
    tool = "; ".join(f"{t}: bit {d.bit_diameter_mm:g} x {d.bit_length_mm:g} mm, handle {d.handle_diameter_mm:g} mm"
                     for t, d in ((t, fastener_table().size(t).driver) for t in sorted({j.thread for j in joints.values()})))
    details.append(f"drivers ({tool})")
    details += [f"step {st.number} '{st.id}': {sum(1 for n in st.nodes if n in joints)} screws" for st in steps]
    return OrderReport(len(joints), bad, details, data)
