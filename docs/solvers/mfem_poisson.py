"""MFEM (PyMFEM, `pip install mfem`): -Δu = f on triwild's order-3 mesh read
from the .msh file (`mfem.Mesh(path)`: cubic geometry, element attributes =
physical surface tags, boundary attributes = physical curve tags; the names are
the file's $PhysicalNames; MSH 2.2, see VERSION), u = 0 on the curve `disk-curve`, the source
integrated over the regions `disk` and `core` through an attribute marker.
Prints the L2 and H1 errors of P1, P2, P3 at three sizes and checks the
optimal rates (L2: k + 1, H1: k) and the exact area.

    python docs/solvers/mfem_poisson.py
"""

from __future__ import annotations

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402

try:
    import mfem.ser as mfem
    import scipy.sparse
    import scipy.sparse.linalg
except ImportError:
    common.skip("PyMFEM is not installed (pip install mfem)")


class Exact(mfem.PyCoefficient):
    def EvalValue(self, x):
        return float(common.exact(x[0], x[1]))


class Source(mfem.PyCoefficient):
    def EvalValue(self, x):
        return float(common.source(x[0], x[1]))


class ExactGrad(mfem.VectorPyCoefficient):
    def EvalValue(self, x):
        return [float(g) for g in common.exact_grad(x[0], x[1])]


# MFEM reads MSH 2.2 and 4.1 (ASCII) at order 3. A boundary element has one
# attribute: in 4.1 an edge of two physical curves (the outer circle is
# `disk-curve` and `boundary`) is one line element and MFEM gives it one
# attribute, `boundary`'s (shared_edge_attributes checks it); 2.2 writes the
# line once per curve, so each curve's attribute covers all its edges.
VERSION = "2.2"


def physical_names(path: str) -> dict[str, int]:
    """{name: tag} of the file's $PhysicalNames (the attributes' names)."""
    names, lines = {}, open(path).read().split("$PhysicalNames\n", 1)[1].splitlines()
    for line in lines[1 : 1 + int(lines[0])]:
        dim, tag, name = line.split(" ", 2)
        names[name.strip('"')] = int(tag)
    return names


def marker(size: int, tags) -> "mfem.intArray":
    m = mfem.intArray([0] * size)
    for t in tags:
        m[t - 1] = 1
    return m


def run(k: int, path: str):
    names = physical_names(path)
    mesh = mfem.Mesh(path, 1, 1)
    geometry_order = mesh.GetNodalFESpace().GetMaxElementOrder()
    assert geometry_order == 3, geometry_order
    fes = mfem.FiniteElementSpace(mesh, mfem.H1_FECollection(k, 2))
    dirichlet = marker(mesh.bdr_attributes.Max(), [names["disk-curve"]])
    ess = mfem.intArray()
    fes.GetEssentialTrueDofs(dirichlet, ess)
    exact, source = Exact(), Source()
    regions = marker(mesh.attributes.Max(), [names["disk"], names["core"]])
    b = mfem.LinearForm(fes)
    b.AddDomainIntegrator(mfem.DomainLFIntegrator(source, 1, k + 6), regions)
    b.Assemble()
    x = mfem.GridFunction(fes)
    x.Assign(0.0)  # u = 0 on disk-curve
    a = mfem.BilinearForm(fes)
    a.AddDomainIntegrator(mfem.DiffusionIntegrator())
    a.Assemble()
    A, B, X = mfem.SparseMatrix(), mfem.Vector(), mfem.Vector()
    a.FormLinearSystem(ess, x, b, A, X, B)
    # MFEM's CSR matrix, solved by scipy's direct solver
    csr = scipy.sparse.csr_matrix((A.GetDataArray(), A.GetJArray(), A.GetIArray()), shape=(A.Height(), A.Width()))
    X.Assign(scipy.sparse.linalg.spsolve(csr.tocsc(), B.GetDataArray()))
    a.RecoverFEMSolution(X, b, x)
    rules = [mfem.IntRules.Get(g, 2 * k + 6) for g in range(mfem.Geometry.NumGeom)]
    l2 = x.ComputeL2Error(exact, rules)
    h1 = x.ComputeGradError(ExactGrad(2), rules)
    one = mfem.ConstantCoefficient(1.0)
    ones = mfem.GridFunction(fes)
    ones.ProjectCoefficient(one)
    lf = mfem.LinearForm(fes)
    lf.AddDomainIntegrator(mfem.DomainLFIntegrator(one, 0, 8))
    lf.Assemble()
    area = lf * ones
    return fes.GetTrueVSize(), l2, h1, area


def shared_edge_attributes() -> dict[str, int]:
    """Boundary elements per curve name when MFEM reads MSH 4.1."""
    path = common.msh_file(3, common.LEVELS[0], version="4.1")
    names = {tag: name for name, tag in physical_names(path).items()}
    mesh = mfem.Mesh(path, 1, 1)
    counts = {name: 0 for name in ("boundary", "disk-curve", "core-curve")}
    for i in range(mesh.GetNBE()):
        counts[names[mesh.GetBdrAttribute(i)]] += 1
    return counts


def main() -> None:
    failures: list[str] = []
    counts = shared_edge_attributes()
    print(f"MSH 4.1: boundary elements per attribute {counts} (the outer circle is boundary and disk-curve)")
    common.expect(counts["disk-curve"] == 0 < counts["boundary"], "MSH 4.1: the shared edges are boundary only", failures)
    paths = [common.msh_file(3, level, version=VERSION) for level in common.LEVELS]
    for k in (1, 2, 3):
        rows = []
        for level, path in zip(common.LEVELS, paths):
            n, l2, h1, area = run(k, path)
            rows.append((n, l2, h1))
            common.expect(abs(area - common.AREA) < 1e-9, f"area {area!r} at -l {level}", failures)
        l2_rate, h1_rate = common.table(f"MFEM P{k} on order-3 geometry", rows)[-1]
        common.expect(l2_rate > k + 1 - 0.3, f"P{k}: L2 rate {l2_rate:.2f} < {k + 0.7}", failures)
        common.expect(h1_rate > k - 0.3, f"P{k}: H1 rate {h1_rate:.2f} < {k - 0.3}", failures)
    common.finish(failures)


if __name__ == "__main__":
    main()
