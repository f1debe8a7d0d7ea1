"""PNG renders of the assembly with VTK, off screen (EGL or OSMesa: no display needed)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .assembly import Assembly
from .geom import moved


def _vtk():
    import vtk
    vtk.vtkObject.GlobalWarningDisplayOff()   # the X11 probe warns before VTK falls back to EGL
    return vtk


def _actor(vtk, shape, colour, tolerance):
    from vtk.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray
    verts, tris = shape.tessellate(tolerance, 0.3)
    pts = vtk.vtkPoints()
    pts.SetData(numpy_to_vtk(np.array([v.toTuple() for v in verts], dtype=float), deep=True))
    t = np.asarray(tris, dtype=np.int64).reshape(-1, 3)
    cells = vtk.vtkCellArray()
    conn = np.hstack([np.full((len(t), 1), 3, dtype=np.int64), t]).ravel()
    cells.SetCells(len(t), numpy_to_vtkIdTypeArray(conn, deep=True))
    poly = vtk.vtkPolyData()
    poly.SetPoints(pts)
    poly.SetPolys(cells)
    mapper = vtk.vtkPolyDataMapper()
    mapper.SetInputData(poly)
    actor = vtk.vtkActor()
    actor.SetMapper(mapper)
    actor.GetProperty().SetColor(*colour[:3])
    actor.GetProperty().SetInterpolationToFlat()
    return actor


def _placed(vtk, poly, colour, pose):
    mapper = vtk.vtkPolyDataMapper()
    mapper.SetInputData(poly)
    actor = vtk.vtkActor()
    actor.SetMapper(mapper)
    actor.GetProperty().SetColor(*colour[:3])
    m = vtk.vtkMatrix4x4()
    M = pose.matrix()
    for i in range(4):
        for j in range(4):
            m.SetElement(i, j, float(M[i, j]))
    actor.SetUserMatrix(m)
    return actor


def render_views(asm: Assembly, folder: Path, views: dict, exploded: dict, tolerance: float,
                 size=(1200, 900)) -> list[Path]:
    vtk = _vtk()
    out = []
    meshes: dict = {}
    for view, (direction, explode) in views.items():
        ren = vtk.vtkRenderer()
        ren.SetBackground(1, 1, 1)
        for n in asm.nodes:
            pose = exploded[n.name] if explode else n.pose
            key = id(n.spec)
            if key not in meshes:
                meshes[key] = _actor(vtk, n.local_shape(asm.cache), n.colour, tolerance).GetMapper().GetInput()
            ren.AddActor(_placed(vtk, meshes[key], n.colour, pose))
        win = vtk.vtkRenderWindow()
        win.SetOffScreenRendering(1)
        win.AddRenderer(ren)
        win.SetSize(*size)
        cam = ren.GetActiveCamera()
        d = np.asarray(direction, dtype=float)
        d /= np.linalg.norm(d)
        cam.SetFocalPoint(0, 0, 0)
        cam.SetPosition(*(d * 1000))
        cam.SetViewUp(*((0, 0, 1) if abs(d[2]) < 0.99 else (1, 0, 0)))
        ren.ResetCamera()
        cam.Zoom(1.3)
        win.Render()
        grab = vtk.vtkWindowToImageFilter()
        grab.SetInput(win)
        grab.Update()
        writer = vtk.vtkPNGWriter()
        p = folder / f"{view}.png"
        writer.SetFileName(str(p))
        writer.SetInputConnection(grab.GetOutputPort())
        writer.Write()
        win.Finalize()
        out.append(p)
    return out
