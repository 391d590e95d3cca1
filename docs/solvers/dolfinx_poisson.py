"""dolfinx: -Δu = f on triwild's order-3 mesh read through gmsh's API
(`gmsh.open`, then `dolfinx.io.gmsh.model_to_mesh`: cubic geometry, cell tags
from the physical surfaces, facet tags from the physical curves, names from
`physical_groups`), u = 0 on the curve `disk-curve`, the source
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
    cmap = msh.geometry.cmaps[0] if hasattr(msh.geometry, "cmaps") else msh.geometry.cmap
    assert cmap.degree == 3, cmap.degree
    V = fem.functionspace(msh, ("Lagrange", k))
    x = ufl.SpatialCoordinate(msh)
    exact = (1 - x[0] ** 2 - x[1] ** 2) * ufl.exp(x[0])
    f = (3 + 4 * x[0] + x[0] ** 2 + x[1] ** 2) * ufl.exp(x[0])
    dx = ufl.Measure("dx", domain=msh, subdomain_data=cells, metadata={"quadrature_degree": 2 * k + 6})
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    a = ufl.inner(ufl.grad(u), ufl.grad(v)) * dx
    L = ufl.inner(f, v) * dx(groups["disk"].tag) + ufl.inner(f, v) * dx(groups["core"].tag)
    outer = facets.find(groups["disk-curve"].tag)
    assert len(outer) > 0, "the facets of disk-curve"
    bc = fem.dirichletbc(default_scalar_type(0), fem.locate_dofs_topological(V, 1, outer), V)
    uh = LinearProblem(
        a, L, bcs=[bc], petsc_options_prefix="p", petsc_options={"ksp_type": "preonly", "pc_type": "lu"}
    ).solve()
    if isinstance(uh, tuple):
        uh = uh[0]
    q = ufl.dx(domain=msh, metadata={"quadrature_degree": 2 * k + 6})
    e = uh - exact
    l2 = fem.assemble_scalar(fem.form(ufl.inner(e, e) * q)).real
    h1 = fem.assemble_scalar(fem.form(ufl.inner(ufl.grad(e), ufl.grad(e)) * q)).real
    area = fem.assemble_scalar(fem.form(fem.Constant(msh, default_scalar_type(1.0)) * ufl.dx(domain=msh))).real
    return V.dofmap.index_map.size_global, np.sqrt(l2), np.sqrt(h1), area


def _lines_per_curve(path: str) -> dict[str, list]:
    """The line elements of each physical curve, as gmsh's API lists them."""
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        gmsh.open(path)
        out = {}
        for dim, tag in gmsh.model.getPhysicalGroups(1):
            out[gmsh.model.getPhysicalName(dim, tag)] = [
                e for entity in gmsh.model.getEntitiesForPhysicalGroup(dim, tag)
                for e in gmsh.model.mesh.getElements(dim, entity)[1][0]
            ]
        return out
    finally:
        gmsh.finalize()


def main() -> None:
    failures: list[str] = []
    paths = [common.msh_file(3, level) for level in common.LEVELS]
    data = read(paths[0])
    tags = {name: len(data.facet_tags.find(g.tag)) for name, g in data.physical_groups.items() if g.dim == 1}
    lines = {name: len(triangles) for name, triangles in _lines_per_curve(paths[0]).items()}
    print(f"facet tags (facets per curve): {tags}; line elements in the file: {lines}")
    # a facet on two curves keeps one tag: the shape's curve, not `boundary`
    common.expect(tags == {**lines, "boundary": 0}, "facet tags: the shape's curves whole, boundary none", failures)
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
