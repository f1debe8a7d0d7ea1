"""Exports: the assembly as one STEP with named, coloured parts and a GLB; every printed part as its
own STEP and STL in its print orientation, with its dimensioned drawing (``cad/drawings.py``); SVG line
drawings and PNG renders of the iso, front, top and exploded views. Everything goes into an :class:`~platform_tools.rig.atomic.OutputDir` stage first."""
from __future__ import annotations

import json
from pathlib import Path

import cadquery as cq
import numpy as np

from platform_tools.rig.frames import Pose
from platform_tools.rig.progress import progress

from .assembly import PRINT_SETUPS, Assembly, assembly_tree, camera_frames
from .export_folder import EXPORT_MARKER, write_manifest
from .parts.common import on_bed
from .solids import location, moved

VIEWS = {  # name: (projection direction towards the viewer, exploded)
    "iso": ((1.0, 1.0, 0.8), False),
    "front": ((1.0, 0.0, 0.0), False),
    "top": ((0.0, 0.0, 1.0), False),
    "exploded": ((1.0, 1.0, 0.8), True),
}


def to_cq_assembly(asm: Assembly, poses: dict[str, Pose] | None = None) -> cq.Assembly:
    root = cq.Assembly(name="rig")
    for g in asm.groups():
        sub = cq.Assembly(name=g)
        for n in asm.nodes:
            if n.group != g:
                continue
            pose = (poses or {}).get(n.name, n.pose)
            sub.add(n.local_shape(asm.cache), name=n.name, color=cq.Color(*n.colour), loc=location(pose))
        root.add(sub, name=g)
    return root


def exploded_poses(asm: Assembly) -> dict[str, Pose]:
    d = asm.layout.c.exploded_mm
    offsets = {"case": None, "handles": None, "power": (0, 0, -d), "cameras": (d, 0, 0), "cooling": (d * 0.5, 0, 0),
               "mounts": (d * 0.5, 0, -d * 0.3), "controls": (-d * 0.3, 0, d * 0.3), "compute": (0, 0, 0)}
    out = {}
    for n in asm.nodes:
        off = offsets.get(n.group)
        if n.name == "case_lid" or n.name.startswith("handle_"):
            off = (0, 0, 1.5 * d)
            if n.name in ("handle_left", "handle_right"):
                off = (0, (1 if n.name.endswith("left") else -1) * d, 1.5 * d)
        elif n.group == "fasteners":
            host = n.props.get("host", "")
            off = (0, 0, 1.5 * d) if host == "case_lid" else (0, 0, 0)
        if off is None:
            off = (0, 0, 0)
        out[n.name] = Pose(np.eye(3), np.asarray(off, dtype=float)) @ n.pose
    return out


def write_step(asm: Assembly, path: Path) -> None:
    to_cq_assembly(asm).export(str(path), "STEP")


def write_glb(asm: Assembly, path: Path, tolerance: float) -> None:
    to_cq_assembly(asm).export(str(path), "GLTF", tolerance=tolerance, angularTolerance=0.2)


def write_printed(asm: Assembly, folder: Path, tolerance: float, angular: float, formats: set[str]) -> list[Path]:
    folder.mkdir(parents=True, exist_ok=True)
    bed = asm.rig.desc.printing.printer.bed_mm
    out = []
    for pid, n in progress(list(asm.printed().items()), desc="printed parts"):
        shape = n.local_shape(asm.cache)
        if n.category == "printed" and pid in PRINT_SETUPS:
            shape, _ = on_bed(shape, PRINT_SETUPS[pid], bed)
        if "STEP" in formats:
            p = folder / f"{pid}.step"
            cq.exporters.export(shape, str(p), "STEP")
            out.append(p)
        if "STL" in formats:
            p = folder / f"{pid}.stl"
            cq.exporters.export(shape, str(p), "STL", tolerance=tolerance, angularTolerance=angular)
            out.append(p)
    return out


def write_svgs(asm: Assembly, folder: Path) -> list[Path]:
    folder.mkdir(parents=True, exist_ok=True)
    out = []
    exploded = exploded_poses(asm)
    for view, (direction, explode) in progress(list(VIEWS.items()), desc="svg views"):
        shapes = [moved(n.local_shape(asm.cache), exploded[n.name] if explode else n.pose)
                  for n in asm.nodes if n.group != "fasteners"]
        comp = cq.Compound.makeCompound(shapes)
        p = folder / f"{view}.svg"
        cq.exporters.export(comp, str(p), "SVG", opt={"projectionDir": direction, "showHidden": False,
                                                       "width": 900, "height": 700, "strokeWidth": 0.3})
        out.append(p)
    return out


def write_pngs(asm: Assembly, folder: Path, tolerance: float) -> list[Path]:
    from .render import render_views
    folder.mkdir(parents=True, exist_ok=True)
    return render_views(asm, folder, VIEWS, exploded_poses(asm), tolerance)


def write_metadata(asm: Assembly, folder: Path) -> list[Path]:
    """The assembly tree (for the BOM) and the camera optical frames (for the CAD extrinsics)."""
    tree = assembly_tree(asm)
    frames = {k: dict(matrix=np.round(v.matrix(), 9).tolist(), xyz_mm=v.t.tolist(), rpy_deg=list(v.rpy_deg()))
              for k, v in camera_frames(asm).items()}
    a = folder / "assembly_tree.json"
    a.write_text(json.dumps(tree, indent=1) + "\n")
    b = folder / "camera_frames.json"
    b.write_text(json.dumps(dict(frame="rig (x forward, y left, z up, mm)", rig_hash=asm.rig.hash, frames=frames),
                            indent=1) + "\n")
    return [a, b]


def export_key(asm: Assembly, formats: set[str], tolerance: float, angular: float) -> str:
    """What the exported files depend on: every node (its part's cache key, pose, colour, name), the
    options, and the code of the exporters."""
    import hashlib
    from . import cache as cache_mod
    h = hashlib.sha256()
    for n in asm.nodes:
        h.update(f"{n.name}|{n.part_id}|{n.group}|{cache_mod.key(n.spec)}|{n.pose.matrix().tobytes().hex()}|{n.colour}|"
                 f"{sorted(n.props.items())}".encode())
    h.update(f"{sorted(formats)}|{tolerance!r}|{angular!r}|{asm.rig.hash}".encode())
    for mod in ("cad.export", "cad.render", "cad.assembly", "cad.parts.common", "cad.drawings", "cad.drawing_holes"):
        h.update(cache_mod._module_source_hash(mod).encode())
    return h.hexdigest()[:32]


def export(asm: Assembly, stage: Path, formats: set[str], tolerance: float = 0.1, angular: float = 0.2) -> list[Path]:
    """Write the requested formats into ``stage`` (a staging folder); reuse an identical earlier export
    from the build cache when nothing it depends on changed."""
    import shutil
    cached = asm.cache.folder / "exports" / export_key(asm, formats, tolerance, angular) if asm.cache.enabled else None
    if cached is not None and (cached / "DONE").exists():
        shutil.copytree(cached, stage, dirs_exist_ok=True)
        (stage / "DONE").unlink()
        write_manifest(asm, stage)
        asm.cache.hits += 1
        return sorted(p for p in stage.rglob("*") if p.is_file() and p.name != EXPORT_MARKER)
    out = _export(asm, stage, formats, tolerance, angular)
    if cached is not None:
        try:
            tmp = cached.with_name(cached.name + ".tmp")
            shutil.rmtree(tmp, ignore_errors=True)
            shutil.copytree(stage, tmp)
            (tmp / "DONE").write_text("")
            shutil.rmtree(cached, ignore_errors=True)
            tmp.rename(cached)
        except OSError:
            pass  # the cache is an optimisation
    return out


def _export(asm: Assembly, stage: Path, formats: set[str], tolerance: float, angular: float) -> list[Path]:
    out: list[Path] = []
    if "STEP" in formats:
        p = stage / "rig_assembly.step"
        write_step(asm, p)
        out.append(p)
    if formats & {"STEP", "STL"}:
        out += write_printed(asm, stage / "printed", tolerance, angular, formats)
    if "GLB" in formats:
        p = stage / "rig_assembly.glb"
        write_glb(asm, p, max(tolerance, 0.2))
        out.append(p)
    if "SVG" in formats:
        from .drawings import write_drawings
        out += write_svgs(asm, stage / "views")
        out += write_drawings(asm, stage / "printed")   # the dimensioned drawings, beside each part's STEP/STL
    if "PNG" in formats:
        out += write_pngs(asm, stage / "views", max(tolerance, 0.3))
    out += write_metadata(asm, stage)
    write_manifest(asm, stage)
    return out
