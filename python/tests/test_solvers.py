"""What the solvers get from Python: the background mesh in memory
(``size_from=(points, triangles, h)``), the VTK file (``write_vtu``, read back
by ``vtk`` when it is installed) and the scikit-fem mesh (``to_skfem``) with
named subdomains and boundaries."""

from __future__ import annotations

import numpy as np
import pytest

import triwild
from conftest import REPO

PLATE = REPO / "tests" / "fixtures" / "plate.svg"
BASE = dict(cut_outside=True, edge_length_abs=5)


def with_node_data(path, h) -> None:
    """Append a gmsh view of one value per node to the MSH 2.2 ASCII file at `path`."""
    rows = "".join(f"{i + 1} {float(v)!r}\n" for i, v in enumerate(h))
    with open(path, "a") as f:
        f.write(f'$NodeData\n1\n"h"\n1\n0.0\n3\n0\n1\n{len(h)}\n{rows}$EndNodeData\n')


def test_size_from_in_memory_gives_the_mesh_of_the_same_file(tmp_path):
    bg = triwild.mesh(PLATE, order=1, **BASE)
    h = 0.8 + 0.04 * bg.points[:, 0] + 0.02 * np.abs(bg.points[:, 1])
    path = tmp_path / "bg.msh"
    bg.write(path, version="2.2")
    with_node_data(path, h)
    from_file = triwild.mesh(PLATE, size_from=path, **BASE)
    in_memory = triwild.mesh(PLATE, size_from=(bg.points, bg.triangles, h), **BASE)
    np.testing.assert_array_equal(in_memory.points, from_file.points)
    np.testing.assert_array_equal(in_memory.triangles, from_file.triangles)
    assert len(in_memory.triangles) > len(triwild.mesh(PLATE, **BASE).triangles)
    assert "size-from" in in_memory.stats["sizing"]["fields"]
    # a curved background mesh: its corners are used
    curved = triwild.mesh(PLATE, order=3, **BASE)
    hc = 0.8 + 0.04 * curved.points[:, 0] + 0.02 * np.abs(curved.points[:, 1])
    triwild.mesh(PLATE, size_from=(curved.points, curved.triangles, hc), **BASE)


def test_size_from_refuses_bad_sizes_and_shapes():
    bg = triwild.mesh(PLATE, order=1, **BASE)
    h = np.ones(len(bg.points))
    h[7] = -1.0
    with pytest.raises(triwild.BadInput, match=r"size_from: the size at point 7 .* is -1"):
        triwild.mesh(PLATE, size_from=(bg.points, bg.triangles, h), **BASE)
    with pytest.raises(triwild.BadInput, match="sizes for"):
        triwild.mesh(PLATE, size_from=(bg.points, bg.triangles, h[:-1]), **BASE)
    with pytest.raises(ValueError, match="triangles must be"):
        triwild.mesh(PLATE, size_from=(bg.points, bg.triangles[:, :2], h), **BASE)
    with pytest.raises(ValueError, match="outside"):
        triwild.mesh(PLATE, size_from=(bg.points[:5], bg.triangles, h[:5]), **BASE)
    with pytest.raises(TypeError):
        triwild.mesh(PLATE, size_from=(bg.points, bg.triangles), **BASE)
    # a background that does not cover the drawing
    small = (bg.points * 0.1, bg.triangles, np.ones(len(bg.points)))
    with pytest.raises(triwild.BadInput, match="does not cover"):
        triwild.mesh(PLATE, size_from=small, **BASE)


@pytest.mark.parametrize("order", [1, 2, 3])
def test_write_vtu_is_read_by_vtk_with_the_exact_area(tmp_path, order):
    vtk = pytest.importorskip("vtk")
    from vtk.util.numpy_support import vtk_to_numpy

    m = triwild.mesh(PLATE, order=order, **BASE)
    path = tmp_path / "plate.vtu"
    triwild.write_vtu(m, path)
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(path))
    reader.Update()
    grid = reader.GetOutput()
    nt, nl = len(m.triangles), len(m.lines)
    assert grid.GetNumberOfPoints() == len(m.points)
    assert grid.GetNumberOfCells() == nt + nl
    types = [grid.GetCellType(i) for i in range(nt + nl)]
    assert types == [69] * nt + [68] * nl  # VTK_LAGRANGE_TRIANGLE, VTK_LAGRANGE_CURVE
    assert {grid.GetCell(i).GetNumberOfPoints() for i in range(nt)} == {m.triangles.shape[1]}
    np.testing.assert_array_equal(vtk_to_numpy(grid.GetCellData().GetArray("region"))[:nt], m.region + 1)
    np.testing.assert_array_equal(vtk_to_numpy(grid.GetCellData().GetArray("curve"))[nt:], m.line_tags + 1)
    fd = grid.GetFieldData()
    names = {fd.GetArrayName(i): list(vtk_to_numpy(fd.GetArray(i))) for i in range(fd.GetNumberOfArrays())}
    assert names["steel"] == [m.region_names.index("steel") + 1, 2]
    assert names["boundary"] == [m.line_names.index("boundary") + 1, 1]
    # the area with VTK's own shape functions (its node order) against the exact one
    g, w = np.polynomial.legendre.leggauss(4)
    g, w = (g + 1) / 2, w / 2
    area = 0.0
    for i in range(nt):
        cell = grid.GetCell(i)
        n = cell.GetNumberOfPoints()
        xy = np.array([cell.GetPoints().GetPoint(j)[:2] for j in range(n)])
        for u, wu in zip(g, w):
            for v, wv in zip(g, w):
                d = [0.0] * (2 * n)
                cell.InterpolateDerivs([u, v * (1 - u), 0.0], d)
                J = np.asarray(d).reshape(2, n) @ xy
                area += wu * wv * (1 - u) * (J[0, 0] * J[1, 1] - J[0, 1] * J[1, 0])
    assert area == pytest.approx(m.stats["quality"]["area"], rel=1e-9, abs=0)


@pytest.mark.parametrize("order", [1, 2])
def test_to_skfem_names_subdomains_and_boundaries(order):
    skfem = pytest.importorskip("skfem")
    m = triwild.mesh(PLATE, order=order, **BASE)
    mesh = triwild.to_skfem(m)
    assert isinstance(mesh, skfem.MeshTri1 if order == 1 else skfem.MeshTri2)
    assert set(mesh.subdomains) == set(m.region_names)
    for k, name in enumerate(m.region_names):
        np.testing.assert_array_equal(mesh.subdomains[name], np.flatnonzero(m.region == k))
    assert set(mesh.boundaries) == {n for k, n in enumerate(m.line_names) if np.any(m.line_tags == k)}
    for k, name in enumerate(m.line_names):
        facets = mesh.boundaries[name]
        assert len(facets) == np.sum(m.line_tags == k)
        # each facet joins the two ends of one of the curve's lines
        ends = {frozenset(map(tuple, m.points[line[:2]])) for line in m.lines[m.line_tags == k]}
        assert {frozenset(map(tuple, mesh.p[:, f].T)) for f in mesh.facets[:, facets].T} == ends
    # the boundary curve is the mesh's boundary
    np.testing.assert_array_equal(np.sort(mesh.boundaries["boundary"]), np.sort(mesh.boundary_facets()))
    with pytest.raises(ValueError, match="cubic"):
        triwild.to_skfem(triwild.mesh(PLATE, order=3, **BASE))
