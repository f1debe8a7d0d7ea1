"""Pictures of the assembly guide, rendered from the CAD model with VTK (off screen, EGL).

Each step's picture is an exploded view (``cad.export.exploded_poses``) of the nodes added so far:
what the step adds in the highlight colour, what was already in place faded. A step that adds nodes
gets a close-up too: the same scene framed on the new parts, with a callout per fastener size it
drives ("4 x M3 x 8", at the first of those screws), counted from the model. The overview pictures of
the index page are cad.render's own views.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from platform_tools.rig.frames import Pose

from cad.solids import bounds_of, moved
from cad.render import node_polydata, placed_actor, polydata, snapshot, vtk_module

HIGHLIGHT = (0.12, 0.47, 0.95)   # blue: nothing else in the rig is blue (PETG orange, copper, black parts)
FADE = 0.6                       # earlier parts: blended this far towards light grey


def render_steps(asm, steps, folder: Path, *, size=(960, 640), tolerance: float = 0.25,
                 meshes: dict | None = None) -> list[Path]:
    """One PNG per step (``step_NN.png``): nodes so far in the exploded view, the new ones highlighted. ``meshes``:
    the parts' triangles (cad.render.node_polydata), shared with the other pictures of ``asm``."""
    from cad.export import exploded_poses
    vtk = vtk_module()
    folder.mkdir(parents=True, exist_ok=True)
    exploded = exploded_poses(asm)
    nodes = {n.name: n for n in asm.nodes}
    meshes = {} if meshes is None else meshes
    done: list[str] = []
    out = []
    for st in steps:
        ren = vtk.vtkRenderer()
        ren.SetBackground(1, 1, 1)
        ren.SetBackground2(0.88, 0.91, 0.95)
        ren.GradientBackgroundOn()
        new = set(st.nodes)
        for name in done + st.nodes:
            n = nodes[name]
            if name in new:
                colour, opacity = HIGHLIGHT, 1.0
            else:
                c = np.asarray(n.colour[:3])
                colour, opacity = tuple(c * (1 - FADE) + np.array([0.85, 0.86, 0.88]) * FADE), 0.55
            ren.AddActor(placed_actor(vtk, node_polydata(vtk, asm, n, tolerance, meshes), colour, exploded[name],
                                      opacity))
        done.extend(st.nodes)
        p = snapshot(vtk, ren, st.view, size, folder / f"step_{st.number:02d}.png", zoom=1.25, alpha=True)
        st.picture = f"img/{p.name}"
        out.append(p)
        if st.nodes:
            st.callouts = callouts(asm, st, exploded)
            for k, c in enumerate(st.callouts):   # staggered: an insert and its screw share a point
                ren.AddActor2D(_caption(vtk, c, k))
            box = framed_bounds([bounds_of(moved(nodes[m].local_shape(asm.cache), exploded[m])) for m in st.nodes])
            p = snapshot(vtk, ren, st.view, size, folder / f"step_{st.number:02d}_close.png", zoom=1.25, alpha=True,
                         bounds=box)
            st.closeup = f"img/{p.name}"
            out.append(p)
    return out


def render_cables(asm, steps, folder: Path, *, size=(960, 640), tolerance: float = 0.25,
                  meshes: dict | None = None) -> list[Path]:
    """``step_NN_cables.png`` for every step that lays cables: the rig as assembled by then (faded, not
    exploded: cables run between parts in place) and the step's cables, swept, in the highlight colour,
    framed on them, each labelled with its name and the length bought. ``meshes``: as :func:`render_steps`'."""
    from cad.bought.cables import cable_table
    from cad.cables import routes, sweep
    vtk = vtk_module()
    folder.mkdir(parents=True, exist_ok=True)
    nodes = {n.name: n for n in asm.nodes}
    by_name = {r.name: r for r in routes(asm)}
    table = cable_table().kinds
    meshes = {} if meshes is None else meshes
    done: list[str] = []
    out = []
    for st in steps:
        done.extend(st.nodes)
        if not st.cables:
            continue
        ren = vtk.vtkRenderer()
        ren.SetBackground(1, 1, 1)
        for name in done:
            n = nodes[name]
            if n.group == "fasteners":
                continue
            c = np.asarray(n.colour[:3])
            ren.AddActor(placed_actor(vtk, node_polydata(vtk, asm, n, tolerance, meshes),
                                      tuple(c * (1 - FADE) + np.array([0.85, 0.86, 0.88]) * FADE), n.pose, 0.35))
        boxes = []
        for k, c in enumerate(st.cables):
            r = by_name[c["route"]]
            solid = sweep(r, table[r.kind])
            boxes.append(bounds_of(solid))
            ren.AddActor(placed_actor(vtk, polydata(vtk, solid, 0.1), HIGHLIGHT, Pose.identity()))
            mid = r.points[len(r.points) // 2]
            ren.AddActor2D(_caption(vtk, dict(text=f"{r.name} {c['bought_mm']:g} mm", at=mid), k % 3))
        p = snapshot(vtk, ren, st.view, size, folder / f"step_{st.number:02d}_cables.png", zoom=1.2, alpha=True,
                     bounds=framed_bounds(boxes))
        st.cable_picture = f"img/{p.name}"
        out.append(p)
    return out


#: a close-up frames the step's new parts with this much room around them (fraction of their size, min mm)
CLOSEUP_MARGIN, CLOSEUP_MIN_MM = 0.05, 10.0


def framed_bounds(boxes) -> tuple[float, ...]:
    """VTK bounds around ``boxes`` (cad.geom.Bounds), grown by the close-up margin."""
    lo = np.min([b.lo for b in boxes], axis=0)
    hi = np.max([b.hi for b in boxes], axis=0)
    grow = np.maximum((hi - lo) * CLOSEUP_MARGIN, CLOSEUP_MIN_MM / 2)
    lo, hi = lo - grow, hi + grow
    return (lo[0], hi[0], lo[1], hi[1], lo[2], hi[2])


def callouts(asm, st, exploded) -> list[dict]:
    """One label per fastener size the step drives: "4 x M3 x 8" at the first screw of that size (its
    head, in the exploded view), from the model's screws."""
    nodes = {n.name: n for n in asm.nodes}
    groups: dict[str, list[str]] = {}
    for name in st.nodes:
        n = nodes[name]
        if n.category == "fastener" and "length_mm" in n.props:
            groups.setdefault(f"{n.props['thread']} x {n.props['length_mm']:g}", []).append(name)
        elif n.category == "fastener":
            groups.setdefault(f"insert {n.props['thread']}", []).append(name)
    out = []
    for label, names in groups.items():
        at = exploded[names[0]].t
        out.append(dict(text=f"{len(names)} x {label}", count=len(names), size=label, at=tuple(float(v) for v in at),
                        nodes=names))
    return out


#: each further callout's label stands this much higher above its point (px)
CALLOUT_STAGGER_PX = 30


def _caption(vtk, c: dict, k: int):
    cap = vtk.vtkCaptionActor2D()
    cap.SetPosition(15, 15 + CALLOUT_STAGGER_PX * k)
    cap.SetCaption(c["text"])
    cap.SetAttachmentPoint(*c["at"])
    cap.BorderOff()
    cap.GetCaptionTextProperty().SetColor(0.05, 0.05, 0.05)
    cap.GetCaptionTextProperty().SetFontSize(18)
    cap.GetCaptionTextProperty().BoldOn()
    cap.GetCaptionTextProperty().ShadowOff()
    cap.SetWidth(0.16)
    cap.SetHeight(0.04)
    cap.GetProperty().SetColor(0.8, 0.1, 0.1)
    return cap


def render_overview(asm, folder: Path, tolerance: float = 0.25, meshes: dict | None = None) -> list[Path]:
    """iso, front, top and exploded views of the whole rig (cad.render's own renderer); ``meshes``: as
    :func:`render_steps`'."""
    from cad.export import VIEWS, exploded_poses
    from cad.render import render_views
    folder.mkdir(parents=True, exist_ok=True)
    return render_views(asm, folder, VIEWS, exploded_poses(asm), tolerance, size=(1000, 750), meshes=meshes)
