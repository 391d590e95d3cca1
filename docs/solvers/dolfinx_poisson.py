"""dolfinx: -Δu = f on triwild's order-3 mesh read through gmsh's API
(`gmsh.open`, then `dolfinx.io.gmsh.model_to_mesh`: cubic geometry, cell tags
from the physical surfaces, facet tags from the physical curves, names from
`physical_groups`), u = u_exact on the curve `disk-curve`, the source
integrated over the regions `disk` and `core` by their tags. Prints the L2 and
H1 errors of P1, P2, P3 at three sizes and checks the optimal rates (L2:
k + 1, H1: k) and the exact area.

Needs Python 3.12 with `pip install dolfinx-solver gmsh`; its MPI library sits
in the venv's lib/: run with LD_LIBRARY_PATH=<venv>/lib.

    python docs/solvers/dolfinx_poisson.py
"""

from __future__ import annotations

import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402

try:
    import gmsh
    import ufl
    from dolfinx import default_scalar_type, fem
    from dolfinx.fem.petsc import LinearProblem
    from dolfinx.io import gmsh as gmshio
    from mpi4py import MPI
except ImportError as e:
    common.skip(f"dolfinx or gmsh is not installed ({e}; Python 3.12: pip install dolfinx-solver gmsh)")


def read(path: str):
    """The mesh, its cell and facet tags and the physical names, through gmsh's API."""
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        gmsh.open(path)
        return gmshio.model_to_mesh(gmsh.model, MPI.COMM_WORLD, 0, gdim=2)
    finally:
        gmsh.finalize()


def run(k: int, path: str):
    data = read(path)
    msh, cells, facets, groups = data.mesh, data.cell_tags, data.facet_tags, data.physical_groups
    assert msh.geometry.cmap.degree == 3, msh.geometry.cmap.degree
    V = fem.functionspace(msh, ("Lagrange", k))
    x = ufl.SpatialCoordinate(msh)
    exact = ufl.sin(ufl.pi * x[0]) * ufl.cos(ufl.pi * x[1])
    f = 2 * ufl.pi**2 * exact
    dx = ufl.Measure("dx", domain=msh, subdomain_data=cells, metadata={"quadrature_degree": 2 * k + 6})
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    a = ufl.inner(ufl.grad(u), ufl.grad(v)) * dx
    L = f * v * dx(groups["disk"].tag) + f * v * dx(groups["core"].tag)
    uD = fem.Function(V)
    uD.interpolate(lambda p: common.exact(p[0], p[1]))
    outer = facets.find(groups["disk-curve"].tag)
    assert len(outer) > 0, "the facets of disk-curve"
    bc = fem.dirichletbc(uD, fem.locate_dofs_topological(V, 1, outer))
    uh = LinearProblem(
        a, L, bcs=[bc], petsc_options_prefix="p", petsc_options={"ksp_type": "preonly", "pc_type": "lu"}
    ).solve()
    if isinstance(uh, tuple):
        uh = uh[0]
    q = ufl.dx(domain=msh, metadata={"quadrature_degree": 2 * k + 6})
    l2 = fem.assemble_scalar(fem.form((uh - exact) ** 2 * q))
    h1 = fem.assemble_scalar(fem.form(ufl.inner(ufl.grad(uh - exact), ufl.grad(uh - exact)) * q))
    area = fem.assemble_scalar(fem.form(fem.Constant(msh, default_scalar_type(1.0)) * ufl.dx(domain=msh)))
    return V.dofmap.index_map.size_global, np.sqrt(l2), np.sqrt(h1), area


def main() -> None:
    failures: list[str] = []
    paths = [common.msh_file(3, level) for level in common.LEVELS]
    for k in (1, 2, 3):
        rows = []
        for level, path in zip(common.LEVELS, paths):
            n, l2, h1, area = run(k, path)
            rows.append((n, l2, h1))
            common.expect(abs(area - common.AREA) < 1e-9, f"area {area!r} at -l {level}", failures)
        l2_rate, h1_rate = common.table(f"dolfinx P{k} on order-3 geometry", rows)[-1]
        common.expect(l2_rate > k + 1 - 0.3, f"P{k}: L2 rate {l2_rate:.2f} < {k + 0.7}", failures)
        common.expect(h1_rate > k - 0.3, f"P{k}: H1 rate {h1_rate:.2f} < {k - 0.3}", failures)
    common.finish(failures)


if __name__ == "__main__":
    main()
