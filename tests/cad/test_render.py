"""cad.render's triangles are the shape's: VTK's cells hold the tessellation's triangles, checked against the
shape's own tessellation and its area (an independent path: OpenCascade's surface area of the B-rep)."""
import cadquery as cq
import numpy as np
import pytest

from cad.render import polydata, vtk_module


@pytest.fixture(scope="module")
def vtk():
    return vtk_module()


def _triangle_area_mm2(points: np.ndarray, cells: np.ndarray) -> float:
    a, b, c = (points[cells[:, i]] for i in range(3))
    return float(0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum())


def _points_and_triangles(vtk, poly) -> tuple[np.ndarray, np.ndarray]:
    """(points (N, 3), triangles (M, 3) of point indices) of a VTK polydata; every cell must be a triangle."""
    from vtk.util.numpy_support import vtk_to_numpy
    ids = vtk.vtkIdList()
    cells = []
    for i in range(poly.GetNumberOfCells()):
        poly.GetCellPoints(i, ids)
        assert ids.GetNumberOfIds() == 3
        cells.append([ids.GetId(j) for j in range(3)])
    return vtk_to_numpy(poly.GetPoints().GetData()), np.array(cells)


def test_a_box_is_twelve_triangles_with_its_area_and_bounds(vtk):
    box = cq.Workplane().box(30, 20, 10).val()
    poly = polydata(vtk, box, 0.1)
    assert poly.GetNumberOfPolys() == 12
    assert poly.GetBounds() == pytest.approx((-15, 15, -10, 10, -5, 5))
    assert _triangle_area_mm2(*_points_and_triangles(vtk, poly)) == pytest.approx(box.Area(), rel=1e-9)


def test_a_cylinder_keeps_every_triangle_of_its_tessellation(vtk):
    cyl = cq.Workplane().cylinder(12, 8).val()
    verts, tris = cyl.tessellate(0.05, 0.3)
    poly = polydata(vtk, cyl, 0.05)
    assert poly.GetNumberOfPolys() == len(tris)
    # the normals filter may split vertices at sharp edges, so compare areas, not indices
    want = _triangle_area_mm2(np.array([v.toTuple() for v in verts]), np.asarray(tris))
    assert _triangle_area_mm2(*_points_and_triangles(vtk, poly)) == pytest.approx(want, rel=1e-12)
    assert want == pytest.approx(cyl.Area(), rel=0.01)
