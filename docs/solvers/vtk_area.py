"""VTK / ParaView: `triwild.write_vtu` (the command line's `--format vtu`) read
back with `vtk.vtkXMLUnstructuredGridReader`. For orders 1, 2, 3 checks that
every triangle is a VTK Lagrange triangle (cell type 69) of the mesh's order
and every physical line a Lagrange curve (68), that the cell data `region` and
`curve` and the field data `{name: [tag, dim]}` are the mesh's tags, and that
the area integrated with VTK's own shape functions (so in VTK's node order)
equals the run's exact `quality.area` to 1e-9. ParaView opens the same file.

    python docs/solvers/vtk_area.py
"""

from __future__ import annotations

import os
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402

try:
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy
except ImportError:
    common.skip("vtk is not installed (pip install vtk)")

# collapsed Gauss-Legendre on the reference triangle (exact to degree 7)
_g, _w = np.polynomial.legendre.leggauss(4)
_g, _w = (_g + 1) / 2, _w / 2
RULE = [(u, v * (1 - u), wu * wv * (1 - u)) for u, wu in zip(_g, _w) for v, wv in zip(_g, _w)]


def cell_area(cell) -> float:
    """∫ det J over the reference triangle, with the cell's own shape functions."""
    n = cell.GetNumberOfPoints()
    xy = np.array([cell.GetPoints().GetPoint(i)[:2] for i in range(n)])
    area = 0.0
    for r, s, w in RULE:
        d = [0.0] * (2 * n)
        cell.InterpolateDerivs([r, s, 0.0], d)
        d = np.asarray(d).reshape(2, n)
        J = d @ xy  # rows: d/dr, d/ds of (x, y)
        area += w * (J[0, 0] * J[1, 1] - J[0, 1] * J[1, 0])
    return area


def main() -> None:
    failures: list[str] = []
    folder = tempfile.mkdtemp(prefix="triwild-vtu-")
    for order in (1, 2, 3):
        m = common.mesh(order, 0.05)
        path = os.path.join(folder, f"disk_o{order}.vtu")
        m.write_vtu(path)
        reader = vtk.vtkXMLUnstructuredGridReader()
        reader.SetFileName(path)
        reader.Update()
        grid = reader.GetOutput()
        nt, nl = len(m.triangles), len(m.lines)
        types = np.array([grid.GetCellType(i) for i in range(grid.GetNumberOfCells())])
        common.expect(list(types[:nt]) == [69] * nt and list(types[nt:]) == [68] * nl, f"order {order}: cell types", failures)
        sizes = {grid.GetCell(i).GetNumberOfPoints() for i in range(nt)}
        common.expect(sizes == {(order + 1) * (order + 2) // 2}, f"order {order}: points per triangle {sizes}", failures)
        region = vtk_to_numpy(grid.GetCellData().GetArray("region"))
        curve = vtk_to_numpy(grid.GetCellData().GetArray("curve"))
        common.expect(np.array_equal(region[:nt], m.region + 1), f"order {order}: region tags", failures)
        common.expect(np.array_equal(curve[nt:], m.line_tags + 1), f"order {order}: curve tags", failures)
        fd = grid.GetFieldData()
        names = {fd.GetArrayName(i): tuple(vtk_to_numpy(fd.GetArray(i))) for i in range(fd.GetNumberOfArrays())}
        want = {n: (k + 1, 2) for k, n in enumerate(m.region_names)}
        want.update({n: (k + 1, 1) for k, n in enumerate(m.line_names)})
        common.expect(names == want, f"order {order}: field data {names} != {want}", failures)
        area = sum(cell_area(grid.GetCell(i)) for i in range(nt))
        exact = m.stats["quality"]["area"]
        print(f"order {order}: {nt} Lagrange triangles ({(order + 1) * (order + 2) // 2} points), {nl} Lagrange curves; "
              f"VTK's area {area:.15f}, quality.area {exact:.15f}, difference {abs(area - exact):.1e}")
        common.expect(abs(area - exact) <= 1e-9 * exact, f"order {order}: area {area} != {exact}", failures)
    common.finish(failures)


if __name__ == "__main__":
    main()
