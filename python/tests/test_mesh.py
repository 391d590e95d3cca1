"""triwild.mesh: inputs, arrays against the .msh the command line writes, flags."""

from __future__ import annotations

import inspect
import re
import threading
import time

import meshio
import numpy as np
import pytest

import triwild
from conftest import SVG, run_cli

ELLO = SVG / "ello.svg"


def test_path_bytes_and_str_give_the_same_mesh():
    by_path = triwild.mesh(ELLO, order=2)
    by_str_path = triwild.mesh(str(ELLO), order=2)
    by_bytes = triwild.mesh(ELLO.read_bytes(), order=2)
    by_text = triwild.mesh(ELLO.read_text(), order=2)
    for other in (by_str_path, by_bytes, by_text):
        np.testing.assert_array_equal(other.points, by_path.points)
        np.testing.assert_array_equal(other.triangles, by_path.triangles)
        np.testing.assert_array_equal(other.region, by_path.region)
        assert other.region_names == by_path.region_names


def test_array_shapes_and_types():
    for order, n in ((1, 3), (2, 6), (3, 10)):
        m = triwild.mesh(ELLO, order=order)
        assert m.order == order
        assert m.points.dtype == np.float64 and m.points.shape[1] == 2
        assert m.triangles.dtype == np.int64 and m.triangles.shape[1] == n
        assert m.region.dtype == np.int32 and m.region.shape == (len(m.triangles),)
        assert m.lines.shape[1] == order + 1 and len(m.line_tags) == len(m.lines)
        assert m.triangles.min() >= 0 and m.triangles.max() < len(m.points)
        assert set(np.unique(m.region)) <= set(range(len(m.region_names)))
        assert m.stats["output"]["triangles"] == len(m.triangles)
        assert m.stats["output"]["nodes"] == len(m.points)
        assert m.stats["output"]["order"] == order
        # gmsh order: corners counter-clockwise
        p = m.points[m.triangles[:, :3]]
        cross = (p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1]) - (
            p[:, 1, 1] - p[:, 0, 1]
        ) * (p[:, 2, 0] - p[:, 0, 0])
        assert (cross > 0).all()


CASES = [
    ("ello.svg", {}, []),
    ("ello.svg", {"order": 2, "edge_length": 0.03}, ["--order", "2", "--edge-length", "0.03"]),
    ("ello.svg", {"linear": True}, ["--linear"]),
    ("ello.svg", {"mesher": "cdt", "order": 1}, ["--mesher", "cdt", "--order", "1"]),
    ("ello.svg", {"cut_outside": True, "order": 2}, ["--cut-outside", "--order", "2"]),
    ("ello.svg", {"regions": "none", "eps": 2e-3}, ["--regions", "none", "--eps", "0.002"]),
]


@pytest.mark.parametrize("name,kwargs,flags", CASES)
@pytest.mark.parametrize("version", ["4.1", "2.2"])
def test_arrays_equal_the_cli_msh_node_for_node(tmp_path, name, kwargs, flags, version):
    src = SVG / name
    out = tmp_path / "cli.msh"
    r = run_cli(src, "-o", out, "--msh-version", version, *flags)
    assert r.returncode == 0, r.stderr
    m = triwild.mesh(src, **kwargs)
    ref = meshio.read(out, file_format="gmsh")
    # meshio lists the nodes of a 4.1 file by entity block; the node tags say
    # where each one is in the file's numbering
    pts = ref.points[:, :2]
    if version == "4.1":
        tags = _node_tags_41(out)
        order = np.argsort(tags)
        assert (np.asarray(tags)[order] == np.arange(1, len(tags) + 1)).all()
        inverse = np.empty_like(order)
        inverse[order] = np.arange(len(order))
        pts = pts[order]
    else:
        inverse = np.arange(len(pts))
    np.testing.assert_array_equal(m.points, pts)  # exactly: node for node
    tri_type = {1: "triangle", 2: "triangle6", 3: "triangle10"}[m.order]
    blocks = [(c.data, p) for c, p in zip(ref.cells, ref.cell_data["gmsh:physical"]) if c.type == tri_type]
    tris = np.concatenate([order_of(b, inverse) for b, _ in blocks])
    phys = np.concatenate([p for _, p in blocks])
    np.testing.assert_array_equal(m.triangles, tris)
    np.testing.assert_array_equal(m.region + 1, phys)
    for name_, (tag, dim) in ref.field_data.items():
        names = m.region_names if dim == 2 else m.line_names
        assert names[tag - 1] == name_
    line_type = {1: "line", 2: "line3", 3: "line4"}[m.order]
    if version == "4.1":
        # an edge on several physical curves is one line cell whose entity each
        # of them lists (meshio's cell_sets); compare the edges of each curve
        def edges(ls):
            return {tuple(sorted(l[:2])) for l in ls.tolist()}

        for name_, (tag, dim) in ref.field_data.items():
            if dim != 1:
                continue
            got = set()
            for c, ids in zip(ref.cells, ref.cell_sets[name_]):
                if c.type == line_type and ids is not None and len(ids) > 0:
                    got |= edges(order_of(c.data[ids], inverse))
            assert got == edges(m.lines[m.line_tags + 1 == tag]), name_
        return
    lblocks = [(c.data, p) for c, p in zip(ref.cells, ref.cell_data["gmsh:physical"]) if c.type == line_type]
    lines = np.concatenate([order_of(b, inverse) for b, _ in lblocks])
    ltags = np.concatenate([p for _, p in lblocks])
    key = lambda ls, ts: sorted(zip(ts.tolist(), map(tuple, ls.tolist())))  # noqa: E731
    assert key(m.lines, m.line_tags + 1) == key(lines, ltags)


def order_of(block, inverse):
    return inverse[block]


def _node_tags_41(path):
    """The node tags of an ASCII 4.1 file, in file order."""
    lines = path.read_text().splitlines()
    i = lines.index("$Nodes") + 1
    nblocks = int(lines[i].split()[0])
    i += 1
    tags = []
    for _ in range(nblocks):
        n = int(lines[i].split()[3])
        tags += [int(t) for t in lines[i + 1 : i + 1 + n]]
        i += 1 + 2 * n
    return tags


@pytest.mark.parametrize("version,binary", [("4.1", False), ("4.1", True), ("2.2", False), ("2.2", True)])
def test_write_equals_the_cli_file_byte_for_byte(tmp_path, version, binary):
    flags = ["--msh-version", version] + (["--binary"] if binary else [])
    r = run_cli(ELLO, "-o", tmp_path / "cli.msh", "--order", "2", *flags)
    assert r.returncode == 0, r.stderr
    m = triwild.mesh(ELLO, order=2)
    m.write(tmp_path / "py.msh", version=version, binary=binary)
    assert (tmp_path / "py.msh").read_bytes() == (tmp_path / "cli.msh").read_bytes()
    verdict = triwild.check(tmp_path / "py.msh")
    assert verdict["valid"] is True, verdict


def _help_default(helptext, flag):
    """The `[default: X]` of `flag`'s section of `triwild --help`."""
    lines = helptext.splitlines()
    starts = [i for i, l in enumerate(lines) if re.match(r"\s+(-\w, )?--[\w-]+", l)]
    for k, i in enumerate(starts):
        if re.match(r"\s+(-\w, )?" + re.escape(flag) + r"\b", lines[i]):
            end = starts[k + 1] if k + 1 < len(starts) else len(lines)
            found = re.search(r"\[default: ([^\]]+)\]", "\n".join(lines[i:end]))
            return found.group(1) if found else None
    return None


def test_defaults_are_the_cli_defaults():
    helptext = run_cli("--help").stdout
    sig = inspect.signature(triwild.mesh)
    for name in ("edge_length", "order", "regions", "mesher", "units"):
        flag = "--" + name.replace("_", "-")
        default = _help_default(helptext, flag)
        assert default is not None, f"{flag}: no default in --help"
        assert str(sig.parameters[name].default) == default, (name, default)
    for name in ("cut_outside", "linear"):
        assert sig.parameters[name].default is False
    for name in ("keep", "holes"):
        assert sig.parameters[name].default is None


def test_regions_keep_and_holes(tmp_path):
    svg = (
        '<svg xmlns="http://www.w3.org/2000/svg" width="100" height="100">'
        '<rect id="plate" x="10" y="10" width="80" height="80" fill="grey"/>'
        '<circle id="disk" cx="50" cy="50" r="20" fill="red"/></svg>'
    )
    m = triwild.mesh(svg, order=2, edge_length=0.08)
    assert {"plate", "disk", "background"} <= set(m.region_names)
    kept = triwild.mesh(svg, order=2, edge_length=0.08, keep=["disk"])
    assert [kept.region_names[g] for g in np.unique(kept.region)] == ["disk"]
    # y up: the disk's centre is (50, -50)
    holed = triwild.mesh(svg, order=2, edge_length=0.08, cut_outside=True, holes=[(50.0, -50.0)])
    assert [holed.region_names[g] for g in np.unique(holed.region)] == ["plate"]
    # the same flags on the command line give the same file
    (tmp_path / "in.svg").write_text(svg)
    r = run_cli(tmp_path / "in.svg", "-o", tmp_path / "cli.msh", "--order", "2", "--edge-length",
                "0.08", "--cut-outside", "--hole", "50,-50")
    assert r.returncode == 0, r.stderr
    holed.write(tmp_path / "py.msh")
    assert (tmp_path / "py.msh").read_bytes() == (tmp_path / "cli.msh").read_bytes()


def test_stats_match_the_cli_stats():
    import json

    r = run_cli(ELLO, "-o", "/dev/null", "--stats", "--order", "2")
    assert r.returncode == 0, r.stderr
    cli = json.loads(r.stdout)
    py = triwild.mesh(ELLO, order=2).stats
    for key in ("input", "params", "output", "regions", "mesher"):
        assert py[key] == cli[key], key


def test_meshing_from_four_threads_at_once_releases_the_gil():
    # a drawing that takes a while, meshed on four threads; a fifth thread
    # counts while they run: with the GIL held it could not
    src = ELLO.read_bytes()
    expected = triwild.mesh(src, edge_length=0.02)
    results = [None] * 4
    ticks = [0]
    done = threading.Event()

    def count():
        while not done.is_set():
            ticks[0] += 1
            time.sleep(0.001)

    def work(i):
        results[i] = triwild.mesh(src, edge_length=0.02)

    counter = threading.Thread(target=count)
    counter.start()
    t0 = time.perf_counter()
    threads = [threading.Thread(target=work, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    elapsed = time.perf_counter() - t0
    done.set()
    counter.join()
    for r in results:
        np.testing.assert_array_equal(r.points, expected.points)
        np.testing.assert_array_equal(r.triangles, expected.triangles)
    # the counter ran during the meshing (about one tick per ms when free)
    assert ticks[0] > 0.2 * elapsed * 1000, (ticks[0], elapsed)
