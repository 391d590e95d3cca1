"""Periodic cells from Python (``periodic="xy"``, ``cell=...``): the node pairs
as arrays, bit-identical after the translation; gmsh reads every pair back
(when installed); the laminate's effective conductivities from the
independent solver of ``docs/solvers/periodic_homogenization.py`` (when
meshio and scipy are installed)."""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest

import triwild
from conftest import REPO

CORNER = (
    '<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 1 1">'
    '<circle id="fibre" cx="0" cy="0" r="0.3" fill="#000"/></svg>'
)
LAMINATE = (
    '<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 1 1">'
    '<rect id="stiff" x="0.25" y="0" width="0.5" height="1" fill="#000"/></svg>'
)


def test_pairs_are_the_partners_translated_bit_for_bit():
    m = triwild.mesh(CORNER, periodic="xy")
    assert m.region_names == ["background", "fibre"]
    area = m.stats["regions"]["surfaces"][1]["area"]
    assert abs(area - math.pi * 0.09) < 1e-9 * math.pi * 0.09
    p = m.stats["periodic"]
    assert (p["unpaired"], p["max_mismatch"], p["pairs"]) == (0, 0.0, len(m.periodic_pairs))
    node, partner = m.periodic_pairs.T
    x = m.periodic_axis == 0
    P = m.points
    assert np.array_equal(P[node[x], 1], P[partner[x], 1])
    assert (P[node[x], 0] == 1.0).all() and (P[partner[x], 0] == 0.0).all()
    assert np.array_equal(P[node[~x], 0], P[partner[~x], 0])
    assert (P[node[~x], 1] == 0.0).all() and (P[partner[~x], 1] == -1.0).all()
    # every node on the right side is paired
    assert set(np.flatnonzero(P[:, 0] == 1.0)) == set(node[x])
    for side in ("left", "right", "bottom", "top"):
        assert side in m.line_names


def test_one_axis_and_an_explicit_cell():
    m = triwild.mesh(CORNER, periodic="x", cell=(0, -1, 1, 0))
    assert m.stats["periodic"]["axes"] == "x"
    assert (m.periodic_axis == 0).all() and len(m.periodic_pairs) > 0
    plain = triwild.mesh(CORNER)
    assert plain.periodic_pairs.shape == (0, 2)
    assert plain.stats["periodic"] is None


def test_bad_cells_are_bad_input():
    with pytest.raises(triwild.BadInput, match="viewBox"):
        triwild.mesh('<svg xmlns="http://www.w3.org/2000/svg" width="9" height="9"><rect width="3" height="3"/></svg>',
                     periodic="xy")
    with pytest.raises(triwild.BadInput, match="cell"):
        triwild.mesh(CORNER, periodic="xy", cell=(0, 0, 0, 1))


def test_gmsh_reads_every_pair(tmp_path):
    gmsh = pytest.importorskip("gmsh")
    m = triwild.mesh(CORNER, periodic="xy", order=1)
    path = tmp_path / "cell.msh"
    m.write(path)
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(path))

        def periodic_pairs():
            pairs = set()
            for dim in (0, 1):
                for _, tag in gmsh.model.getEntities(dim):
                    master, nodes, mnodes, affine = gmsh.model.mesh.getPeriodicNodes(dim, tag)
                    if master != tag:
                        pairs |= {(int(a) - 1, int(b) - 1) for a, b in zip(nodes, mnodes) if a != b}
            return pairs

        pairs = periodic_pairs()
        # gmsh's pairs are ours (theirs add the corners' links to the bottom-left corner)
        ours = {tuple(p) for p in m.periodic_pairs.tolist()}
        assert ours <= pairs
        # refine() keeps them (as for gmsh's own periodic mesh of order 1): as
        # many pairs (gmsh renumbers the nodes), each node its master translated
        gmsh.model.mesh.refine()
        after = periodic_pairs()
        assert len(after) == len(pairs)
        for a, b in after:
            pa, pb = gmsh.model.mesh.getNode(a + 1)[0], gmsh.model.mesh.getNode(b + 1)[0]
            assert (pa[0] - pb[0], pa[1] - pb[1]) in {(1.0, 0.0), (0.0, 1.0), (1.0, 1.0)}
    finally:
        gmsh.finalize()


def test_laminate_gives_the_harmonic_and_arithmetic_means(tmp_path):
    pytest.importorskip("meshio")
    pytest.importorskip("scipy")
    sys.path.insert(0, str(REPO / "docs" / "solvers"))
    import periodic_homogenization as ph

    for order in (1, 2, 3):
        m = triwild.mesh(LAMINATE, periodic="xy", order=order)
        path = tmp_path / f"laminate{order}.msh"
        m.write(path)
        K, _, _ = ph.homogenize(str(path), {"background": 1.0, "stiff": 10.0}, pairs="file")
        assert abs(K[0, 0] - 20 / 11) < 1e-8 * 20 / 11
        assert abs(K[1, 1] - 5.5) < 1e-8 * 5.5


def test_disks_match_a_gmsh_periodic_mesh_of_the_cell(tmp_path):
    pytest.importorskip("gmsh")
    pytest.importorskip("meshio")
    pytest.importorskip("scipy")
    sys.path.insert(0, str(REPO / "docs" / "solvers"))
    import periodic_homogenization as ph

    r = math.sqrt(0.3 / math.pi)
    svg = (
        '<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 1 1">'
        f'<circle id="fibre" cx="0" cy="0" r="{r!r}" fill="#000"/></svg>'
    )
    cond = {"background": 1.0, "fibre": 10.0}
    m = triwild.mesh(svg, periodic="xy", order=3, edge_length=0.025)
    ours = tmp_path / "ours.msh"
    m.write(ours)
    K, _, _ = ph.homogenize(str(ours), cond)
    Kf, _, _ = ph.homogenize(str(ours), cond, pairs="file")
    assert abs(Kf[0, 0] - K[0, 0]) < 1e-12
    theirs = tmp_path / "gmsh.msh"
    ph.gmsh_disk_cell(str(theirs), r, 0.025, 3)
    G, _, _ = ph.homogenize(str(theirs), cond)
    # isotropic, and the same value
    assert abs(K[0, 0] - K[1, 1]) < 1e-6 and abs(K[0, 1]) < 1e-6
    assert abs(K[0, 0] - G[0, 0]) < 1e-4 * G[0, 0]
