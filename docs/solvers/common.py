"""What the solver scripts of this folder share: the drawing, the manufactured
solution, the meshes triwild makes of it, and the table they print.

The drawing is a disk of radius 1 (`disk`) holding an off-centre disk of radius
0.45 (`core`). With `cut_outside=True` the mesh has the regions `disk` and
`core` and the curves `boundary` (the outer circle, the domain's boundary),
`disk-curve` (the same circle: the shape's outline) and `core-curve` (the
inner circle). Each script solves -Δu = f with u = 0 on `disk-curve`, the
source assembled region by region (`disk`, then `core`), for the manufactured
solution u = (1 - x² - y²)·eˣ, f = eˣ·(3 + 4x + x² + y²). u = 0 is imposed on
the mesh's own boundary, so the error holds the geometry's too: a polygon
(order 1) holds P2 to L2 ~ h² and H1 ~ h^1.5, order-3 geometry lets P3
converge at h⁴ and h³.
"""

from __future__ import annotations

import math
import os
import sys
import tempfile

import numpy as np

DISK_SVG = (
    '<svg xmlns="http://www.w3.org/2000/svg" viewBox="-1.25 -1.25 2.5 2.5">'
    '<circle id="disk" cx="0" cy="0" r="1" fill="grey"/>'
    '<circle id="core" cx="0.25" cy="0" r="0.45" fill="red"/></svg>'
)
AREA = math.pi  # the domain's exact area
# edge lengths relative to the drawing's diagonal 2√2: h ≈ 0.14, 0.07, 0.035
LEVELS = (0.05, 0.025, 0.0125)


def exact(x, y):
    return (1 - x**2 - y**2) * np.exp(x)


def exact_grad(x, y):
    return (1 - x**2 - y**2 - 2 * x) * np.exp(x), -2 * y * np.exp(x)


def source(x, y):
    return (3 + 4 * x + x**2 + y**2) * np.exp(x)


def mesh(order: int, level: float):
    """triwild's mesh of the drawing (`cut_outside`), as a `triwild.Mesh`."""
    import triwild

    return triwild.mesh(DISK_SVG, order=order, edge_length=level, cut_outside=True)


def msh_file(order: int, level: float, version: str = "4.1") -> str:
    """The mesh written as a gmsh file in a scratch folder; its path."""
    folder = tempfile.mkdtemp(prefix="triwild-solver-")
    path = os.path.join(folder, f"disk_o{order}_l{level}.msh")
    mesh(order, level).write(path, version=version)
    return path


def skip(why: str) -> None:
    """Say why the script does not run here, and exit 0 (a clean skip)."""
    print(f"SKIPPED: {why}")
    sys.exit(0)


def rates(rows: list[tuple[int, float, float]]) -> list[tuple[float, float]]:
    """Convergence rates in h ~ N^(-1/2) between successive rows of
    (dofs, L2 error, H1 error)."""
    out = [(float("nan"), float("nan"))]
    for (n0, l0, h0), (n1, l1, h1) in zip(rows, rows[1:]):
        s = 0.5 * math.log(n1 / n0)
        out.append((math.log(l0 / l1) / s, math.log(h0 / h1) / s))
    return out


def table(title: str, rows: list[tuple[int, float, float]], levels=LEVELS) -> list[tuple[float, float]]:
    """Print the errors and their rates; return the rates."""
    print(title)
    print(f"  {'-l':>6} {'dofs':>8} {'L2 error':>11} {'rate':>5} {'H1 error':>11} {'rate':>5}")
    r = rates(rows)
    for lev, (n, l2, h1), (rl, rh) in zip(levels, rows, r):
        print(f"  {lev:>6} {n:>8} {l2:>11.3e} {rl:>5.2f} {h1:>11.3e} {rh:>5.2f}")
    return r


def expect(ok: bool, what: str, failures: list[str]) -> None:
    """Record `what` as a failure unless `ok`."""
    if not ok:
        failures.append(what)
        print(f"FAILED: {what}")


def finish(failures: list[str]) -> None:
    """Exit 1 when anything failed, else say so."""
    if failures:
        print(f"{len(failures)} check(s) failed")
        sys.exit(1)
    print("all checks passed")
