"""Mesh.to_meshio(): what meshio reads from the .msh file, and a round trip
through meshio's own writer and reader."""

from __future__ import annotations

import meshio
import numpy as np
import pytest

import triwild
from conftest import SVG


@pytest.mark.parametrize("order", [1, 2, 3])
def test_to_meshio_equals_meshio_reading_the_22_file(tmp_path, order):
    m = triwild.mesh(SVG / "ello.svg", order=order)
    m.write(tmp_path / "m.msh", version="2.2")
    ref = meshio.read(tmp_path / "m.msh")
    mine = m.to_meshio()
    np.testing.assert_array_equal(mine.points, ref.points)
    assert [c.type for c in mine.cells] == [c.type for c in ref.cells]
    for a, b in zip(mine.cells, ref.cells):
        np.testing.assert_array_equal(a.data, b.data)
    for key in ("gmsh:physical", "gmsh:geometrical"):
        assert len(mine.cell_data[key]) == len(ref.cell_data[key])
        for a, b in zip(mine.cell_data[key], ref.cell_data[key]):
            np.testing.assert_array_equal(a, b)
    assert {k: list(v) for k, v in mine.field_data.items()} == {
        k: list(v) for k, v in ref.field_data.items()
    }


@pytest.mark.parametrize("fmt,ext", [("gmsh22", "msh"), ("vtu", "vtu")])
def test_to_meshio_round_trips_through_meshio(tmp_path, fmt, ext):
    m = triwild.mesh(SVG / "ello.svg", order=2, cut_outside=True)
    mine = m.to_meshio()
    path = tmp_path / f"rt.{ext}"
    meshio.write(path, mine, file_format=fmt)
    back = meshio.read(path, file_format="gmsh" if fmt == "gmsh22" else fmt)
    np.testing.assert_array_equal(back.points[:, :2], m.points)
    assert [c.type for c in back.cells] == ["triangle6", "line3"]
    np.testing.assert_array_equal(back.cells[0].data, m.triangles)
    np.testing.assert_array_equal(back.cells[1].data, m.lines)
    for key in ("gmsh:physical", "gmsh:geometrical"):
        for a, b in zip(back.cell_data[key], mine.cell_data[key]):
            np.testing.assert_array_equal(a, b)
    if fmt == "gmsh22":
        assert {k: list(v) for k, v in back.field_data.items()} == {
            k: list(v) for k, v in mine.field_data.items()
        }


def test_cell_sets_are_the_regions():
    m = triwild.mesh(SVG / "ello.svg", order=2)
    mm = m.to_meshio()
    for g, name in enumerate(m.region_names):
        if (m.region == g).any():
            np.testing.assert_array_equal(mm.cell_sets_dict[name]["triangle6"], np.flatnonzero(m.region == g))
    for g, name in enumerate(m.line_names):
        np.testing.assert_array_equal(mm.cell_sets_dict[name]["line3"], np.flatnonzero(m.line_tags == g))
