"""NGSolve (`pip install ngsolve`): -Δu = f on triwild's order-2 mesh read by
netgen's gmsh reader (`netgen.read_gmsh.ReadGmsh`, MSH 2.2 ASCII, 3- and
6-node triangles: order 2 is the highest it takes; materials and boundary
names from the file's $PhysicalNames), u = u_exact on the curve `disk-curve`,
the source integrated over `mesh.Materials("disk|core")`. Prints the L2 and H1
errors of P1, P2 at three sizes and checks the optimal rates (L2: k + 1, H1:
k) and the area.

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
    mesh.Curve(2)  # the 6-node triangles' edge nodes as the geometry
    x, y = ngs.x, ngs.y
    exact = ngs.sin(ngs.pi * x) * ngs.cos(ngs.pi * y)
    grad_exact = ngs.CF((ngs.pi * ngs.cos(ngs.pi * x) * ngs.cos(ngs.pi * y), -ngs.pi * ngs.sin(ngs.pi * x) * ngs.sin(ngs.pi * y)))
    f = 2 * ngs.pi**2 * exact
    fes = ngs.H1(mesh, order=k, dirichlet="disk-curve")
    u, v = fes.TnT()
    a = ngs.BilinearForm(ngs.grad(u) * ngs.grad(v) * ngs.dx).Assemble()
    b = ngs.LinearForm(f * v * ngs.dx(definedon=mesh.Materials("disk|core"), bonus_intorder=4)).Assemble()
    gfu = ngs.GridFunction(fes)
    gfu.Set(exact, ngs.BND, definedon=mesh.Boundaries("disk-curve"))
    r = b.vec - a.mat * gfu.vec
    gfu.vec.data += a.mat.Inverse(fes.FreeDofs(), inverse="sparsecholesky") * r
    l2 = ngs.sqrt(ngs.Integrate((gfu - exact) ** 2, mesh, order=2 * k + 6))
    h1 = ngs.sqrt(ngs.Integrate((ngs.grad(gfu) - grad_exact) ** 2, mesh, order=2 * k + 6))
    area = ngs.Integrate(ngs.CF(1), mesh, order=6)
    return fes.ndof, l2, h1, area


def main() -> None:
    failures: list[str] = []
    paths = [common.msh_file(2, level, version="2.2") for level in common.LEVELS]
    for k in (1, 2):
        rows = []
        for level, path in zip(common.LEVELS, paths):
            n, l2, h1, area = run(k, path)
            rows.append((n, l2, h1))
            common.expect(abs(area - common.AREA) < 2e-3 * level**2, f"area {area!r} at -l {level}", failures)
        l2_rate, h1_rate = common.table(f"NGSolve P{k} on order-2 geometry", rows)[-1]
        common.expect(l2_rate > k + 1 - 0.3, f"P{k}: L2 rate {l2_rate:.2f} < {k + 0.7}", failures)
        common.expect(h1_rate > k - 0.3, f"P{k}: H1 rate {h1_rate:.2f} < {k - 0.3}", failures)
    common.finish(failures)


if __name__ == "__main__":
    main()
