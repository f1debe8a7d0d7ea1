"""Pictures of the assembly guide, rendered from the CAD model with VTK (off screen, EGL).

Each step's picture is an exploded view (``cad.export.exploded_poses``) of the nodes added so far:
what the step adds in the highlight colour, what was already in place faded. The overview pictures of
the index page are cad.render's own views.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from cad.render import placed_actor, polydata, snapshot, vtk_module

HIGHLIGHT = (0.12, 0.47, 0.95)   # blue: nothing else in the rig is blue (PETG orange, copper, black parts)
FADE = 0.6                       # earlier parts: blended this far towards light grey


def render_steps(asm, steps, folder: Path, *, size=(960, 640), tolerance: float = 0.25) -> list[Path]:
    """One PNG per step (``step_NN.png``): nodes so far in the exploded view, the new ones highlighted."""
    from cad.export import exploded_poses
    vtk = vtk_module()
    folder.mkdir(parents=True, exist_ok=True)
    exploded = exploded_poses(asm)
    nodes = {n.name: n for n in asm.nodes}
    meshes: dict[int, object] = {}
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
            key = id(n.spec)
            if key not in meshes:
                meshes[key] = polydata(vtk, n.local_shape(asm.cache), tolerance)
            if name in new:
                colour, opacity = HIGHLIGHT, 1.0
            else:
                c = np.asarray(n.colour[:3])
                colour, opacity = tuple(c * (1 - FADE) + np.array([0.85, 0.86, 0.88]) * FADE), 0.55
            ren.AddActor(placed_actor(vtk, meshes[key], colour, exploded[name], opacity))
        done.extend(st.nodes)
        p = snapshot(vtk, ren, st.view, size, folder / f"step_{st.number:02d}.png", zoom=1.25, alpha=True)
        st.picture = f"img/{p.name}"
        out.append(p)
    return out


def render_overview(asm, folder: Path, tolerance: float = 0.25) -> list[Path]:
    """iso, front, top and exploded views of the whole rig (cad.render's own renderer)."""
    from cad.export import VIEWS, exploded_poses
    from cad.render import render_views
    folder.mkdir(parents=True, exist_ok=True)
    return render_views(asm, folder, VIEWS, exploded_poses(asm), tolerance, size=(1000, 750))
