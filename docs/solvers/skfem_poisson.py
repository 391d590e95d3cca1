"""scikit-fem: -Δu = f on triwild's mesh through `triwild.to_skfem` (order 1
and 2 geometry; scikit-fem has no cubic triangle geometry), u = 0 on the curve
`disk-curve` (its facets by name), the source assembled on the regions `disk`
and `core` by name. Prints the L2 and H1 errors of P1 on order-1 and P1, P2 on
order-2 (isoparametric) meshes at three sizes, and checks the optimal rates
(L2: k + 1, H1: k) and the area.

    python docs/solvers/skfem_poisson.py
"""

from __future__ import annotations

import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402

try:
    import skfem
    from skfem.helpers import dot, grad
except ImportError:
    common.skip("scikit-fem is not installed (pip install scikit-fem)")
import triwild  # noqa: E402


@skfem.BilinearForm
def stiffness(u, v, w):
    return dot(grad(u), grad(v))


@skfem.LinearForm
def load(v, w):
    return common.source(*w.x) * v


@skfem.Functional
def l2_sq(w):
    return (w["uh"] - common.exact(*w.x)) ** 2


@skfem.Functional
def h1_sq(w):
    gx, gy = common.exact_grad(*w.x)
    return (w["uh"].grad[0] - gx) ** 2 + (w["uh"].grad[1] - gy) ** 2


@skfem.Functional
def one(w):
    return 1.0 + 0 * w.x[0]


def run(geometry: int, k: int, level: float):
    """Dofs, squared L2 and H1 errors and the area on the mesh of `level`."""
    mesh = triwild.to_skfem(common.mesh(geometry, level))
    assert set(mesh.subdomains) == {"disk", "core"}, mesh.subdomains.keys()
    assert {"boundary", "disk-curve", "core-curve"} <= set(mesh.boundaries), mesh.boundaries.keys()
    element = {1: skfem.ElementTriP1(), 2: skfem.ElementTriP2()}[k]
    basis = skfem.Basis(mesh, element, intorder=2 * k + 4)
    A = stiffness.assemble(basis)
    b = sum(load.assemble(basis.with_elements(name)) for name in ("disk", "core"))
    D = basis.get_dofs("disk-curve").all()
    u = skfem.solve(*skfem.condense(A, b, D=D))  # u = 0 on disk-curve
    uh = basis.interpolate(u)
    return basis.N, (l2_sq.assemble(basis, uh=uh), h1_sq.assemble(basis, uh=uh), one.assemble(basis))


def main() -> None:
    failures: list[str] = []
    for geometry, k in ((1, 1), (2, 1), (2, 2)):
        rows = []
        for level in common.LEVELS:
            n, (l2sq, h1sq, area) = run(geometry, k, level)
            rows.append((n, np.sqrt(l2sq), np.sqrt(h1sq)))
            if geometry == 2:
                common.expect(abs(area - common.AREA) < 1e-4, f"order-2 area {area}", failures)
        r = common.table(f"scikit-fem P{k} on order-{geometry} geometry ({len(rows)} sizes)", rows)
        l2_rate, h1_rate = r[-1]
        common.expect(l2_rate > k + 1 - 0.3, f"P{k} order {geometry}: L2 rate {l2_rate:.2f} < {k + 1 - 0.3}", failures)
        common.expect(h1_rate > k - 0.3, f"P{k} order {geometry}: H1 rate {h1_rate:.2f} < {k - 0.3}", failures)
    common.finish(failures)


if __name__ == "__main__":
    main()
