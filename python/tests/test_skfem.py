"""What a solver gets from Python: scikit-fem P2 on triwild's order-2 mesh
(isoparametric) converges at the P2 rate on a disk, and the README's example runs."""

from __future__ import annotations

import re

import numpy as np
import pytest

import triwild
from conftest import REPO

skfem = pytest.importorskip("skfem")
from skfem import Basis, BilinearForm, ElementTriP2, Functional, LinearForm, condense, solve  # noqa: E402
from skfem.helpers import dot, grad  # noqa: E402

DISK = (
    '<svg xmlns="http://www.w3.org/2000/svg" viewBox="-1.25 -1.25 2.5 2.5">'
    '<circle id="disk" cx="0" cy="0" r="1"/></svg>'
)


def exact(x, y):
    return np.sin(np.pi * (x**2 + y**2))  # 0 on the unit circle


def source(x, y):
    s = x**2 + y**2  # f = -Δu
    return -(4 * np.pi * np.cos(np.pi * s) - 4 * np.pi**2 * s * np.sin(np.pi * s))


@BilinearForm
def stiffness(u, v, w):
    return dot(grad(u), grad(v))


@LinearForm
def load(v, w):
    return source(*w.x) * v


@Functional
def sq_error(w):
    return (w["uh"] - exact(*w.x)) ** 2


def l2_error(edge_length):
    m = triwild.mesh(DISK, order=2, edge_length=edge_length, cut_outside=True)
    assert m.region_names == ["disk"]
    mesh = skfem.MeshTri2(m.points.T, m.triangles.T)
    basis = Basis(mesh, ElementTriP2(), intorder=8)
    boundary = basis.get_dofs().all()
    u = np.zeros(basis.N)
    u[boundary] = exact(*basis.doflocs[:, boundary])
    u = solve(*condense(stiffness.assemble(basis), load.assemble(basis), x=u, D=boundary))
    area = Functional(lambda w: 1.0 + 0 * w.x[0]).assemble(basis)
    return np.sqrt(sq_error.assemble(basis, uh=basis.interpolate(u))), len(m.triangles), area


def test_p2_on_the_order_2_mesh_converges_at_the_p2_rate():
    levels = [l2_error(l) for l in (0.05, 0.035, 0.025, 0.0175, 0.0125)]
    errors = np.array([e for e, _, _ in levels])
    h = 1 / np.sqrt([n for _, n, _ in levels])
    rate = np.polyfit(np.log(h), np.log(errors), 1)[0]
    print(f"P2 on order 2, disk: errors {errors}, triangles {[n for _, n, _ in levels]}, rate {rate:.2f}")
    assert rate >= 2.6, (rate, errors)
    assert errors[-1] < 2e-4
    # the curved boundary: the area is π to the P2 geometry's accuracy
    assert abs(levels[-1][2] - np.pi) < 1e-6


def test_the_readme_example_runs(tmp_path, monkeypatch):
    readme = (REPO / "README.md").read_text()
    section = readme.split("## From Python", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    assert len(code.strip().splitlines()) <= 10
    import matplotlib

    matplotlib.use("Agg")
    monkeypatch.chdir(tmp_path)
    ns: dict = {}
    exec(compile(code, "README.md", "exec"), ns)
    assert (tmp_path / "heat.png").stat().st_size > 10_000
    # the solution: zero on the boundary, positive inside, hottest in the heater
    u, basis, m = ns["u"], ns["basis"], ns["m"]
    assert set(m.region_names) == {"plate", "heater"}
    hottest = basis.doflocs[:, np.argmax(u)]
    assert np.hypot(hottest[0] - 30, hottest[1] + 30) < 15
    assert u.min() > -1e-9 and u.max() > 100
