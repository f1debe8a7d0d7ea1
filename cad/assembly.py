"""The full rig assembly: every part placed, with its part id, colour and name.

:func:`build` returns an :class:`Assembly` (a list of :class:`Node` in named groups). Each node has
the rig's part id (bought parts and fasteners) or a printed/machined part id, its pose in the rig
frame and its shape. Every screw joint of the layout places its screw (and insert), so a bill of
materials counts fasteners from the geometry: :func:`assembly_tree` is what the BOM reads, and
:func:`camera_frames` gives every camera's optical frame as the assembly places it.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import cadquery as cq
import numpy as np

from platform_tools.rig.frames import Pose
from platform_tools.rig import Rig

from .cache import ShapeCache
from .layout import Layout, layout
from .solids import moved
from .parts import camera_mounts, case, cooling, handle, power_mounts

PETG = (0.93, 0.45, 0.10, 1.0)       # printed parts
PETG_DARK = (0.22, 0.22, 0.24, 1.0)  # case
COPPER = (0.78, 0.45, 0.22, 1.0)
#: the devkit's node: the card's standoffs stand on it
ORIN_NODE = "jetson_agx_orin"

#: print orientation of every printed part id
PRINT_SETUPS = {**case.PRINT, **camera_mounts.PRINT, **cooling.PRINT, **handle.PRINT, **power_mounts.PRINT}


@dataclass
class Node:
    name: str
    part_id: str
    category: str            # bought | printed | machined | fastener
    group: str
    spec: object             # has build(); the cache key
    pose: Pose               # the node's frame in the rig frame
    colour: tuple[float, float, float, float]
    props: dict = field(default_factory=dict)
    optical: dict[str, Pose] = field(default_factory=dict)   # optical frames in the node's frame
    _shape: cq.Shape | None = None

    def local_shape(self, cache: ShapeCache) -> cq.Shape:
        return cache.get(self.spec)

    def shape(self, cache: ShapeCache) -> cq.Shape:
        if self._shape is None:
            self._shape = moved(cache.get(self.spec), self.pose)
        return self._shape


@dataclass
class Assembly:
    rig: Rig
    layout: Layout
    nodes: list[Node]
    cache: ShapeCache

    def node(self, name: str) -> Node:
        for n in self.nodes:
            if n.name == name:
                return n
        raise KeyError(f"no node {name!r} in the assembly")

    def by_part(self, part_id: str) -> list[Node]:
        return [n for n in self.nodes if n.part_id == part_id]

    def groups(self) -> list[str]:
        out: list[str] = []
        for n in self.nodes:
            if n.group not in out:
                out.append(n.group)
        return out

    def printed(self) -> dict[str, Node]:
        """One node per printed (or machined) part id: the part to make."""
        out: dict[str, Node] = {}
        for n in self.nodes:
            if n.category in ("printed", "machined") and n.part_id not in out:
                out[n.part_id] = n
        return out


def build(rig: Rig, cache: ShapeCache | None = None) -> Assembly:
    """Lay out and place every part. Raises :class:`cad.layout.DesignError` for impossible values."""
    lay = layout(rig)
    nodes: list[Node] = []
    I = Pose.identity()

    def add(name, part_id, category, group, spec, pose=I, colour=PETG, **props):
        nodes.append(Node(name, part_id, category, group, spec, pose, colour, props))
        return nodes[-1]

    # cameras
    z = add("zed_x", lay.cameras.zed.part_id, "bought", "cameras", lay.cameras.zed, lay.cameras.zed_pose, lay.cameras.zed.colour)
    z.optical = {f"zed_x_{k}_optical": v for k, v in lay.cameras.zed.optical_frames().items()}
    hs = cooling.heat_sink(lay)
    for side, t in lay.cameras.thermal.items():
        n = add(f"boson_{side}", lay.cameras.core.part_id, "bought", "cameras", lay.cameras.core, t.pose, lay.cameras.core.colour)
        n.optical = {f"thermal_{side}_optical": lay.cameras.core.optical_frames()["optical"]}
        add(f"boson_lens_{side}", lay.cameras.lens.part_id, "bought", "cameras", lay.cameras.lens, t.pose, lay.cameras.lens.colour)
        add(f"sync_breakout_{side}", lay.power.breakout.part_id, "bought", "cameras", lay.power.breakout,
            lay.power.breakout_poses[side], lay.power.breakout.colour)
        add(f"heat_sink_{side}", hs.part_id, "machined", "cooling", hs, t.pose, COPPER,
            material=rig.desc.enclosure.heat_sink.material)
        add(f"boson_clamp_{side}", f"boson_clamp_{side}", "printed", "mounts", camera_mounts.retaining_plate(lay, side),
            t.pose)
        add(f"fan_{side}", lay.cooling.part.part_id, "bought", "cooling", lay.cooling.part, lay.cooling.fans[side].pose,
            lay.cooling.part.colour)
        add(f"fan_mount_{side}", f"fan_mount_{side}", "printed", "cooling", cooling.fan_mount(lay, side))
    add("zed_mount", "zed_mount", "printed", "mounts", camera_mounts.zed_mount(lay))
    add("thermal_mount", "thermal_mount", "printed", "mounts", camera_mounts.thermal_mount(lay))
    # compute
    add(ORIN_NODE, lay.compute.orin.part_id, "bought", "compute", lay.compute.orin, lay.compute.orin_pose, lay.compute.orin.colour)
    add("zed_link_quad", lay.compute.card.part_id, "bought", "compute", lay.compute.card, lay.compute.card_pose, lay.compute.card.colour)
    cs = lay.compute.card_standoff
    for k, pose in enumerate(lay.compute.card_standoff_poses):
        add(f"card_standoff_{k}", cs.part_id, "fastener", "compute", cs, pose, cs.colour, length_mm=cs.length_mm,
            thread=cs.thread, host=ORIN_NODE, kind="standoff")
    so = power_mounts.standoff(lay)
    for k, pt in enumerate(lay.compute.orin.mount_points()):
        p = lay.compute.orin_pose.apply(np.array(pt))
        add(f"orin_standoff_{k}", so.part_id, "printed", "compute", so, Pose(np.eye(3), (p[0], p[1], lay.case.interior.lo[2])))
    # power
    add("dc_converter", lay.power.converter.part_id, "bought", "power", lay.power.converter, lay.power.converter_pose, lay.power.converter.colour)
    add("blade_fuse", lay.power.fuse.part_id, "bought", "power", lay.power.fuse, lay.power.fuse_pose, lay.power.fuse.colour)
    add("cable_gland", lay.power.gland.part_id, "bought", "power", lay.power.gland, lay.power.gland_pose, lay.power.gland.colour)
    add("undervoltage_cutoff", lay.power.cutoff.part_id, "bought", "power", lay.power.cutoff, lay.power.cutoff_pose,
        lay.power.cutoff.colour)
    add("battery_mount", "battery_mount", "printed", "power", power_mounts.battery_mount(lay))
    add("makita_adapter", lay.power.adapter.part_id, "bought", "power", lay.power.adapter, lay.power.adapter_pose, lay.power.adapter.colour)
    add("makita_battery", lay.power.battery.part_id, "bought", "power", lay.power.battery, lay.power.battery_pose, lay.power.battery.colour)
    # controls
    for name, (part, pose) in lay.controls.items():
        add(name, part.part_id, "bought", "controls", part, pose, part.colour)
    # case and handles
    spec = case.case_spec(lay)
    add("case_lower", "case_lower", "printed", "case", case.CaseHalf("case_lower", "lower", spec), colour=PETG_DARK)
    add("case_lid", "case_lid", "printed", "case", case.CaseHalf("case_lid", "upper", spec), colour=PETG_DARK)
    hd = handle.handle(lay)
    for name, pose in lay.handles.poses.items():
        add(f"handle_{name}", hd.part_id, "printed", "handles", hd, pose)
    # fasteners, from the joints
    _add_fasteners(lay, add)
    return Assembly(rig, lay, nodes, cache or ShapeCache())


def _add_fasteners(lay: Layout, add) -> None:
    """The screw (and insert) each joint holds, as placed nodes whose spec is the fastener itself."""
    for j in lay.joints:
        screw = j.screw
        add(f"screw_{j.name}", screw.part_id, "fastener", "fasteners", screw, j.pose(), screw.colour,
            length_mm=j.length_mm, thread=j.thread, joint=j.name, host=j.host, kind=j.kind)
        if j.insert is not None:
            ins = j.insert
            add(f"insert_{j.name}", ins.part_id, "fastener", "fasteners", ins, j.insert_pose(), ins.colour,
                thread=j.thread, joint=j.name, host=j.host)


# ---------------------------------------------------------------------------- views for other tools
def camera_frames(asm: Assembly) -> dict[str, Pose]:
    """Every camera's optical frame (x right, y down, z forward) in the rig frame, read from the same
    placement the geometry uses."""
    out = {}
    for n in asm.nodes:
        for name, T in n.optical.items():
            out[name] = n.pose @ T
    return out


def print_volume_mm3(asm: Assembly, node: Node) -> float:
    return node.local_shape(asm.cache).Volume()


def assembly_tree(asm: Assembly, *, volumes: bool = True) -> dict:
    """The assembly as a tree for a bill of materials: groups of leaves, each with its part id, a
    quantity of 1, its pose (4x4, mm) and its properties (a screw's length); per printed part id its
    volume, mass and print orientation; and the count of every part id."""
    rig = asm.rig
    groups = []
    for g in asm.groups():
        leaves = [dict(name=n.name, part_id=n.part_id, category=n.category, quantity=1,
                       placement=np.round(n.pose.matrix(), 6).tolist(), props=n.props)
                  for n in asm.nodes if n.group == g]
        groups.append(dict(name=g, children=leaves))
    counts: dict[str, int] = {}
    for n in asm.nodes:
        key = n.spec.bom_key if n.category == "fastener" else n.part_id
        counts[key] = counts.get(key, 0) + 1
    printed = {}
    p = rig.desc.printing.printer
    for pid, n in asm.printed().items():
        entry = dict(category=n.category, quantity=len(asm.by_part(pid)))
        if volumes:
            v = print_volume_mm3(asm, n)
            dens = rig.desc.enclosure.heat_sink.density_g_cm3 if n.category == "machined" else p.density_g_cm3
            entry.update(volume_mm3=round(v, 1), mass_g=round(v / 1000 * dens, 1))
        if pid in PRINT_SETUPS:
            s = PRINT_SETUPS[pid]
            entry.update(print_orientation_rpy_deg=list(s.rpy_deg), print_note=s.why)
        printed[pid] = entry
    return dict(name="rig", rig_hash=rig.hash, children=groups, counts=counts, made_parts=printed)
