"""PNG renders of the assembly with VTK, off screen (EGL or OSMesa: no display needed)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .assembly import Assembly


def vtk_module():
    """VTK, quiet: the X11 probe warns before VTK falls back to EGL."""
    import vtk
    vtk.vtkObject.GlobalWarningDisplayOff()
    return vtk


def polydata(vtk, shape, tolerance: float):
    """A CadQuery shape as VTK triangles with smoothed normals (sharp edges kept past 35 deg)."""
    from vtk.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray
    verts, tris = shape.tessellate(tolerance, 0.3)
    pts = vtk.vtkPoints()
    pts.SetData(numpy_to_vtk(np.array([v.toTuple() for v in verts], dtype=float).reshape(-1, 3), deep=True))
    t = np.asarray(tris, dtype=np.int64).reshape(-1, 3)
    cells = vtk.vtkCellArray()
    offsets = np.arange(0, 3 * len(t) + 1, 3, dtype=np.int64)     # VTK 9's layout: offsets and connectivity
    cells.SetData(numpy_to_vtkIdTypeArray(offsets, deep=True), numpy_to_vtkIdTypeArray(t.ravel(), deep=True))
    poly = vtk.vtkPolyData()
    poly.SetPoints(pts)
    poly.SetPolys(cells)
    normals = vtk.vtkPolyDataNormals()
    normals.SetInputData(poly)
    normals.SetFeatureAngle(35)
    normals.Update()
    return normals.GetOutput()


def node_polydata(vtk, asm: Assembly, node, tolerance: float, meshes: dict):
    """:func:`polydata` of a node's part in its own frame, tessellated once per part and tolerance: ``meshes``
    (one dict for every picture of one assembly) keeps them. The guide's cable pictures re-tessellated every part
    already assembled, for each step (tessellation was 21.7 of a 74 s docs build, cProfile)."""
    key = (id(node.spec), tolerance)
    if key not in meshes:
        meshes[key] = polydata(vtk, node.local_shape(asm.cache), tolerance)
    return meshes[key]


def placed_actor(vtk, poly, colour, pose, opacity: float = 1.0):
    """An actor drawing ``poly`` at ``pose`` (a Pose in the rig frame)."""
    mapper = vtk.vtkPolyDataMapper()
    mapper.SetInputData(poly)
    actor = vtk.vtkActor()
    actor.SetMapper(mapper)
    prop = actor.GetProperty()
    prop.SetColor(*colour[:3])
    prop.SetOpacity(opacity)
    prop.SetAmbient(0.25)
    prop.SetDiffuse(0.75)
    m = vtk.vtkMatrix4x4()
    M = pose.matrix()
    for r in range(4):
        for c in range(4):
            m.SetElement(r, c, float(M[r, c]))
    actor.SetUserMatrix(m)
    return actor


def snapshot(vtk, ren, direction, size, path: Path, *, zoom: float, alpha: bool = False, bounds=None) -> Path:
    """Render ``ren`` off screen, looking at the origin from ``direction`` (z up), into a PNG; framed on
    ``bounds`` (xmin, xmax, ymin, ymax, zmin, zmax) when given, else on everything."""
    win = vtk.vtkRenderWindow()
    win.SetOffScreenRendering(1)
    if alpha:
        win.SetAlphaBitPlanes(1)
    win.AddRenderer(ren)
    win.SetSize(*size)
    cam = ren.GetActiveCamera()
    d = np.asarray(direction, dtype=float)
    d /= np.linalg.norm(d)
    cam.SetFocalPoint(0, 0, 0)
    cam.SetPosition(*(d * 1000))
    cam.SetViewUp(*((0, 0, 1) if abs(d[2]) < 0.99 else (1, 0, 0)))
    if bounds is not None:
        cx, cy, cz = ((bounds[0] + bounds[1]) / 2, (bounds[2] + bounds[3]) / 2, (bounds[4] + bounds[5]) / 2)
        cam.SetFocalPoint(cx, cy, cz)
        cam.SetPosition(*(np.array([cx, cy, cz]) + d * 1000))
        ren.ResetCamera(*bounds)
    else:
        ren.ResetCamera()
    cam.Zoom(zoom)
    win.Render()
    grab = vtk.vtkWindowToImageFilter()
    grab.SetInput(win)
    grab.Update()
    writer = vtk.vtkPNGWriter()
    writer.SetFileName(str(path))
    writer.SetInputConnection(grab.GetOutputPort())
    writer.Write()
    win.Finalize()
    return path


def render_views(asm: Assembly, folder: Path, views: dict, exploded: dict, tolerance: float,
                 size=(1200, 900), meshes: dict | None = None) -> list[Path]:
    """``meshes``: :func:`node_polydata`'s, shared with the caller's other pictures of ``asm``."""
    vtk = vtk_module()
    out = []
    meshes = {} if meshes is None else meshes
    for view, (direction, explode) in views.items():
        ren = vtk.vtkRenderer()
        ren.SetBackground(1, 1, 1)
        for n in asm.nodes:
            pose = exploded[n.name] if explode else n.pose
            ren.AddActor(placed_actor(vtk, node_polydata(vtk, asm, n, tolerance, meshes), n.colour, pose))
        p = folder / f"{view}.png"
        snapshot(vtk, ren, direction, size, p, zoom=1.3)
        out.append(p)
    return out
