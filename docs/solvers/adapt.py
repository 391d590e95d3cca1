"""An adaptive loop with triwild as the remesher: -Δu = 0 on the L-shaped
domain (-1, 1)² minus [0, 1) × (-1, 0], u = r^(2/3) sin(2θ/3) on the boundary
(the corner singularity at the origin), Pk in scikit-fem for k = 1, 2, 3.

Each step solves on the current mesh, estimates the error per element with the
residual estimator of the gradient's jumps (η_T² = ½ Σ_{E ⊂ T} h_E ‖[∂u_h/∂n]‖²_E
over interior edges), turns it into a size field by equidistribution (η_T ≈
C_T h_T^(k+1): h_new = h_T (η*/η_T)^(1/(k+1)), η* chosen so that the new mesh
has about GROWTH times as many triangles; at a vertex the geometric mean of its
triangles' sizes), and remeshes the drawing with
`triwild.mesh(..., size_from=(points, triangles, h))`: the current mesh's
vertices and the new sizes there, in memory. A background mesh must cover the
drawing's bounding box, the L's missing quadrant too, so the vertices and the
box's corners (at the largest size) are triangulated by scipy's Delaunay. The H1 error then falls as N^(-k/2) in
the number of dofs N (uniform refinement: N^(-1/3), the singularity's rate).

Beside it, the same solver on gmsh's graded meshes of the same domain
(h = H·r^(1 - (2/3)/(k+1)), the grading that is optimal for Pk), when gmsh is
installed. Prints both tables and checks the adaptive rates (≥ k/2 - 0.15
over the last half of the steps).

    python docs/solvers/adapt.py [--steps 12] [--orders 1,2,3]
"""

from __future__ import annotations

import math
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

# the L in SVG coordinates (y down): output (x, y) = (x_svg, -y_svg)
L_SVG = (
    '<svg xmlns="http://www.w3.org/2000/svg" viewBox="-1 -1 2 2">'
    '<path id="L" d="M 0 0 L 1 0 L 1 -1 L -1 -1 L -1 1 L 0 1 Z" fill="grey"/></svg>'
)
GROWTH = 1.8  # triangles: new mesh / current mesh (as the size field predicts them)
START = 0.2  # the first mesh's edge length, relative to the diagonal 2√2
# the smallest edge triwild may make, relative to the diagonal: below its
# default (1e-4) so that the corner's elements can shrink as P3 asks
MIN_EDGE = 1e-9
MAX_DOFS = 60_000  # the loop stops after the first solve above this
ELEMENTS = {1: skfem.ElementTriP1, 2: skfem.ElementTriP2, 3: skfem.ElementTriP3}


def theta(x, y):
    return np.mod(np.arctan2(y, x), 2 * np.pi)


def exact(x, y):
    return np.hypot(x, y) ** (2 / 3) * np.sin(2 * theta(x, y) / 3)


def exact_grad(x, y):
    r, t = np.maximum(np.hypot(x, y), 1e-300), theta(x, y)
    c = 2 / 3 * r ** (-1 / 3)
    return -c * np.sin(t / 3), c * np.cos(t / 3)


@skfem.BilinearForm
def stiffness(u, v, w):
    return dot(grad(u), grad(v))


@skfem.Functional
def h1_sq(w):
    gx, gy = exact_grad(*w.x)
    return (w["uh"].grad[0] - gx) ** 2 + (w["uh"].grad[1] - gy) ** 2


@skfem.Functional
def jump_sq(w):
    j = dot(w["u0"].grad - w["u1"].grad, w.n)
    return w.h * j**2


def solve(mesh, k: int):
    """Pk on `mesh`: the solution's basis and dofs, and the H1 error."""
    basis = skfem.Basis(mesh, ELEMENTS[k](), intorder=2 * k + 4)
    D = basis.get_dofs().all()
    u = np.zeros(basis.N)
    u[D] = exact(*basis.doflocs[:, D])
    u = skfem.solve(*skfem.condense(stiffness.assemble(basis), np.zeros(basis.N), x=u, D=D))
    err = math.sqrt(h1_sq.assemble(basis, uh=basis.interpolate(u)))
    return basis, u, err


def estimate(mesh, basis, u, k: int) -> np.ndarray:
    """η_T per triangle (the jump residual)."""
    sides = [skfem.InteriorFacetBasis(mesh, ELEMENTS[k](), side=i, intorder=2 * k + 2) for i in (0, 1)]
    per_facet = jump_sq.elemental(sides[0], u0=sides[0].interpolate(u), u1=sides[1].interpolate(u))
    facets = sides[0].find
    eta_sq = np.zeros(mesh.t.shape[1])
    for side in (0, 1):
        np.add.at(eta_sq, mesh.f2t[side, facets], 0.5 * per_facet)
    return np.sqrt(eta_sq)


def sizes(mesh, eta: np.ndarray, k: int, target: float) -> np.ndarray:
    """The new size at each vertex: equidistributed η over about `target` triangles."""
    p, t = mesh.p, mesh.t
    e = np.stack([p[:, t[1]] - p[:, t[0]], p[:, t[2]] - p[:, t[1]], p[:, t[0]] - p[:, t[2]]])
    area = 0.5 * np.abs(e[0][0] * e[2][1] - e[0][1] * e[2][0])
    h = np.sqrt(4 / math.sqrt(3) * area)  # the side of the equilateral triangle of that area
    eta = np.maximum(eta, 1e-300)
    # N(η*) = Σ area / (√3/4 h_new²), h_new = h (η*/η)^(1/(k+1))
    s = np.sum(area / (math.sqrt(3) / 4 * h**2) * eta ** (2 / (k + 1)))
    star = (s / target) ** ((k + 1) / 2)
    h_new = h * (star / eta) ** (1 / (k + 1))
    # the mean of log h over the triangles at a vertex
    log_sum, count = np.zeros(p.shape[1]), np.zeros(p.shape[1])
    for corner in range(3):
        np.add.at(log_sum, t[corner], np.log(h_new))
        np.add.at(count, t[corner], 1)
    return np.exp(log_sum / count)


def covering(points: np.ndarray, h: np.ndarray):
    """A background mesh over the drawing's box: Delaunay triangles of `points`
    and the box's corners (size: the largest of `h`)."""
    from scipy.spatial import Delaunay

    lo, hi = points.min(axis=0) - 0.01, points.max(axis=0) + 0.01
    corners = np.array([[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]])
    p = np.vstack([points, corners])
    return p, Delaunay(p).simplices, np.concatenate([h, np.full(4, h.max())])


def to_skfem(m) -> "skfem.MeshTri1":
    return skfem.MeshTri1(m.points.T.copy(), m.triangles[:, :3].T.copy())


def adaptive(k: int, steps: int) -> list[tuple[int, int, float]]:
    rows = []
    m = triwild.mesh(L_SVG, order=1, edge_length=START, cut_outside=True)
    for step in range(steps):
        mesh = to_skfem(m)
        basis, u, err = solve(mesh, k)
        rows.append((len(m.triangles), basis.N, err))
        if step + 1 == steps or basis.N > MAX_DOFS:
            break
        h = sizes(mesh, estimate(mesh, basis, u, k), k, GROWTH * len(m.triangles))
        m = triwild.mesh(L_SVG, order=1, edge_length=START, cut_outside=True,
                         min_edge_length=MIN_EDGE, size_from=covering(mesh.p.T, h))
    return rows


def uniform(k: int) -> list[tuple[int, int, float]]:
    rows = []
    for level in (0.1, 0.05, 0.025):
        mesh = to_skfem(triwild.mesh(L_SVG, order=1, edge_length=level, cut_outside=True))
        basis, _, err = solve(mesh, k)
        rows.append((mesh.t.shape[1], basis.N, err))
    return rows


def gmsh_graded(k: int, scales) -> list[tuple[int, int, float]] | None:
    """The same solver on gmsh's meshes graded toward the corner, or None without gmsh."""
    try:
        import gmsh
    except ImportError:
        return None
    rows = []
    for H in scales:
        gmsh.initialize()
        gmsh.option.setNumber("General.Terminal", 0)
        pts = [(0, 0), (1, 0), (1, 1), (-1, 1), (-1, -1), (0, -1)]
        tags = [gmsh.model.geo.addPoint(x, y, 0) for x, y in pts]
        lines = [gmsh.model.geo.addLine(tags[i], tags[(i + 1) % 6]) for i in range(6)]
        gmsh.model.geo.addPlaneSurface([gmsh.model.geo.addCurveLoop(lines)])
        gmsh.model.geo.synchronize()
        beta = 1 - (2 / 3) / (k + 1)
        gmsh.model.mesh.setSizeCallback(lambda dim, tag, x, y, z, lc: H * max(math.hypot(x, y), 1e-6) ** beta)
        for o in ("Mesh.MeshSizeExtendFromBoundary", "Mesh.MeshSizeFromPoints", "Mesh.MeshSizeFromCurvature"):
            gmsh.option.setNumber(o, 0)
        gmsh.model.mesh.generate(2)
        tags_, xyz, _ = gmsh.model.mesh.getNodes()
        index = {int(t): i for i, t in enumerate(tags_)}
        _, _, tri = gmsh.model.mesh.getElements(2)
        gmsh.finalize()
        t = np.vectorize(index.get)(np.asarray(tri[0]).reshape(-1, 3)).T
        mesh = skfem.MeshTri1(np.ascontiguousarray(xyz.reshape(-1, 3)[:, :2].T), np.ascontiguousarray(t))
        basis, _, err = solve(mesh, k)
        rows.append((mesh.t.shape[1], basis.N, err))
    return rows


def slope(rows, first: int = 0) -> float:
    """The fitted exponent of H1 error vs dofs over rows[first:]."""
    n = np.log([r[1] for r in rows[first:]])
    e = np.log([r[2] for r in rows[first:]])
    return float(np.polyfit(n, e, 1)[0])


def main() -> None:
    steps = int(sys.argv[sys.argv.index("--steps") + 1]) if "--steps" in sys.argv else 12
    orders = [int(a) for a in sys.argv[sys.argv.index("--orders") + 1].split(",")] if "--orders" in sys.argv else [1, 2, 3]
    failures: list[str] = []
    for k in orders:
        rows = adaptive(k, steps)
        uni = uniform(k)
        print(f"P{k}: H1 error vs dofs N (optimal N^{-k / 2:.2f}; uniform N^{slope(uni):.2f})")
        print(f"  {'step':>4} {'triangles':>9} {'N':>7} {'H1 error':>10}   (triwild, adaptive)")
        for i, (nt, n, e) in enumerate(rows):
            print(f"  {i:>4} {nt:>9} {n:>7} {e:>10.3e}")
        s = slope(rows, len(rows) // 2)
        print(f"  fitted exponent over steps {len(rows) // 2}..{len(rows) - 1}: {s:.2f}")
        graded = gmsh_graded(k, (0.3, 0.15, 0.075, 0.0375))
        if graded is not None:
            print(f"  {'':>4} {'triangles':>9} {'N':>7} {'H1 error':>10}   (gmsh, graded h = H r^{1 - (2 / 3) / (k + 1):.3f})")
            for nt, n, e in graded:
                print(f"  {'':>4} {nt:>9} {n:>7} {e:>10.3e}")
            print(f"  fitted exponent: {slope(graded):.2f}")
        common.expect(s < -k / 2 + 0.15, f"P{k}: adaptive exponent {s:.2f} is not below {-k / 2 + 0.15:.2f}", failures)
    common.finish(failures)


if __name__ == "__main__":
    main()
