"""NGSolve (`pip install ngsolve`): -Δu = f on triwild's order-1 mesh read by
netgen's gmsh reader (`netgen.read_gmsh.ReadGmsh`, MSH 2.2 ASCII; materials
and boundary names from the file's $PhysicalNames, one per elementary entity,
so MSH 2.2's entity per curve keeps every curve's name), u = 0 on the curve
`disk-curve`, the source integrated over `mesh.Materials("disk|core")`.

Order 1 is the highest a 2D mesh can have there: the reader makes a mesh 3D
(a surface in space) as soon as an element type above 3 appears, and a 6-node
triangle is type 9. So the geometry is the polygon through the curves'
vertices: P1 converges at its optimal rates (L2: 2, H1: 1), P2 is held by the
geometry to about L2: 2, H1: 1.5. Prints both at three sizes and checks that.

    python docs/solvers/ngsolve_poisson.py
"""

from __future__ import annotations

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402

try:
    import ngsolve as ngs
    from netgen.read_gmsh import ReadGmsh
except ImportError:
    common.skip("NGSolve is not installed (pip install ngsolve)")


def run(k: int, path: str):
    mesh = ngs.Mesh(ReadGmsh(path))
    assert {"disk", "core"} <= set(mesh.GetMaterials()), mesh.GetMaterials()
    assert "disk-curve" in mesh.GetBoundaries(), mesh.GetBoundaries()
    x, y = ngs.x, ngs.y
    exact = (1 - x**2 - y**2) * ngs.exp(x)
    grad_exact = ngs.CF(((1 - x**2 - y**2 - 2 * x) * ngs.exp(x), -2 * y * ngs.exp(x)))
    f = (3 + 4 * x + x**2 + y**2) * ngs.exp(x)
    fes = ngs.H1(mesh, order=k, dirichlet="disk-curve")
    u, v = fes.TnT()
    a = ngs.BilinearForm(ngs.grad(u) * ngs.grad(v) * ngs.dx).Assemble()
    b = ngs.LinearForm(f * v * ngs.dx(definedon=mesh.Materials("disk|core"), bonus_intorder=4)).Assemble()
    gfu = ngs.GridFunction(fes)  # u = 0 on disk-curve
    gfu.vec.data = a.mat.Inverse(fes.FreeDofs(), inverse="sparsecholesky") * b.vec
    l2 = ngs.sqrt(ngs.Integrate((gfu - exact) ** 2, mesh, order=2 * k + 6))
    h1 = ngs.sqrt(ngs.Integrate((ngs.grad(gfu) - grad_exact) ** 2, mesh, order=2 * k + 6))
    area = ngs.Integrate(ngs.CF(1), mesh, order=6)
    return fes.ndof, l2, h1, area


def main() -> None:
    failures: list[str] = []
    order2 = ngs.Mesh(ReadGmsh(common.msh_file(2, common.LEVELS[0], version="2.2")))
    print(f"an order-2 file read by ReadGmsh: a mesh of dimension {order2.dim}")
    common.expect(order2.dim == 3, "ReadGmsh makes an order-2 mesh 3D", failures)
    paths = [common.msh_file(1, level, version="2.2") for level in common.LEVELS]
    for k in (1, 2):
        rows = []
        for level, path in zip(common.LEVELS, paths):
            n, l2, h1, area = run(k, path)
            rows.append((n, l2, h1))
            common.expect(abs(area - common.AREA) < 4 * level**2, f"area {area!r} at -l {level}", failures)
        l2_rate, h1_rate = common.table(f"NGSolve P{k} on order-1 geometry", rows)[-1]
        common.expect(l2_rate > 2 - 0.3, f"P{k}: L2 rate {l2_rate:.2f} < 1.7", failures)
        common.expect(h1_rate > min(k, 1.5) - 0.3, f"P{k}: H1 rate {h1_rate:.2f} < {min(k, 1.5) - 0.3}", failures)
    common.finish(failures)


if __name__ == "__main__":
    main()
