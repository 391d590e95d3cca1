"""meshio: the physical groups meshio reads against the ones gmsh's API sees,
and what survives `meshio convert` to XDMF.

1. For every drawing of data/svg, meshed by default and with `cut_outside`, at
   orders 1, 2, 3, written as MSH 4.1 and 2.2: each physical group of gmsh's
   API (`getPhysicalGroups`, `getEntitiesForPhysicalGroup`, `getElements`) is
   a `cell_sets` entry of `meshio.read` with the same elements (compared by
   their nodes' coordinates, as multisets), and no other set is there. The
   per-cell `gmsh:physical` data names one group per element: where two
   physical curves share an edge (with `cut_outside`, a shape's outline and
   `boundary`) the script counts the elements whose `gmsh:physical` names
   each, and prints which name the shared elements get.
2. `meshio convert` of each order's .msh (4.1) to XDMF, read back: the cell
   types, and which of cell data, cell sets and names survive.

    python docs/solvers/meshio_tags.py [--quick]   (--quick: two drawings)
"""

from __future__ import annotations

import glob
import os
import subprocess
import sys
import tempfile
from collections import Counter

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402

try:
    import gmsh
    import meshio
except ImportError as e:
    common.skip(f"meshio and gmsh are needed ({e}; pip install meshio gmsh)")
import triwild  # noqa: E402

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def gmsh_groups(path: str) -> dict[str, Counter]:
    """{physical name: multiset of elements (tuples of node coordinates)} as gmsh's API sees them."""
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        if path.endswith("22.msh"):
            gmsh.option.setNumber("Mesh.CreateTopologyMsh2", 1)
        gmsh.open(path)
        tags, xyz, _ = gmsh.model.mesh.getNodes()
        where = {int(t): (xyz[3 * i], xyz[3 * i + 1]) for i, t in enumerate(tags)}
        out = {}
        for dim, tag in gmsh.model.getPhysicalGroups():
            elements = Counter()
            for entity in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
                for etype, _, nodes in zip(*gmsh.model.mesh.getElements(dim, entity)):
                    n = gmsh.model.mesh.getElementProperties(etype)[3]
                    for row in np.asarray(nodes).reshape(-1, n):
                        elements[tuple(where[int(t)] for t in row)] += 1
            out[gmsh.model.getPhysicalName(dim, tag)] = elements
        return out
    finally:
        gmsh.finalize()


def meshio_groups(m) -> dict[str, Counter]:
    """{cell set name: multiset of elements} as meshio reads them."""
    out = {}
    for name, blocks in m.cell_sets.items():
        elements = Counter()
        for block, idx in zip(m.cells, blocks):
            for row in block.data[np.asarray(idx, dtype=np.int64)]:
                elements[tuple((m.points[i, 0], m.points[i, 1]) for i in row)] += 1
        if elements:
            out[name] = elements
    return out


def physical_counts(m) -> Counter:
    """How many cells `gmsh:physical` gives each name."""
    name_of = {(int(v[1]), int(v[0])): k for k, v in m.field_data.items()}
    dims = {"triangle": 2, "triangle6": 2, "triangle10": 2, "line": 1, "line3": 1, "line4": 1}
    out = Counter()
    for block, tags in zip(m.cells, m.cell_data["gmsh:physical"]):
        for t, c in Counter(tags.tolist()).items():
            out[name_of[(dims[block.type], t)]] += c
    return out


def check_groups(drawings: list[str], folder: str, failures: list[str]) -> None:
    shared_report = set()
    n = 0
    for svg in drawings:
        for cut in (False, True):
            for order in (1, 2, 3):
                m = triwild.mesh(svg, order=order, cut_outside=cut)
                for version in ("4.1", "2.2"):
                    tag = f"{os.path.basename(svg)} order {order}{' --cut-outside' if cut else ''} {version}"
                    path = os.path.join(folder, f"m{n}_{version.replace('.', '')}.msh")
                    n += 1
                    m.write(path, version=version)
                    want = gmsh_groups(path)
                    mm = meshio.read(path)
                    got = meshio_groups(mm)
                    for name in sorted(set(want) | set(got)):
                        if want.get(name) != got.get(name):
                            w, g = want.get(name, Counter()), got.get(name, Counter())
                            common.expect(False, f"{tag}: group {name!r}: gmsh {sum(w.values())} elements, "
                                          f"meshio {sum(g.values())}", failures)
                    # gmsh:physical: the elements of a shared edge carry one name
                    counts = physical_counts(mm)
                    for name, elements in want.items():
                        if counts[name] != sum(elements.values()):
                            shared_report.add((version, name if name == "boundary" else "an outline",
                                               counts[name] < sum(elements.values())))
                print(f"{os.path.basename(svg):>18} order {order}{' --cut-outside' if cut else '              '}: "
                      f"{len(want)} groups, 4.1 and 2.2 agree")
    print(f"{n} files: every physical group of gmsh's API is a meshio cell set with the same elements")
    for version, name, fewer in sorted(shared_report):
        print(f"  MSH {version}: gmsh:physical gives {name} {'fewer' if fewer else 'more'} elements than its group")


def check_xdmf(folder: str, failures: list[str]) -> None:
    print("meshio convert .msh -> .xdmf, read back:")
    for order in (1, 2, 3):
        src = os.path.join(folder, f"disk_o{order}.msh")
        common.mesh(order, 0.1).write(src)
        dst = src.replace(".msh", ".xdmf")
        r = subprocess.run(["meshio", "convert", src, dst], capture_output=True, text=True)
        if r.returncode != 0:
            print(f"  order {order}: meshio convert fails: {r.stderr.strip().splitlines()[-1]}")
            continue
        back = meshio.read(dst)
        types = [c.type for c in back.cells]
        data = sorted(back.cell_data)
        print(f"  order {order}: cells {types}; cell data {data}; cell sets {sorted(back.cell_sets) or 'none'}; "
              f"field data (names) {sorted(back.field_data) or 'none'}")
        orig = meshio.read(src)
        same = all(np.array_equal(a, b) for a, b in zip(orig.cell_data["gmsh:physical"], back.cell_data.get("gmsh:physical", [])))
        common.expect(same, f"order {order}: gmsh:physical survives the conversion", failures)


def main() -> None:
    failures: list[str] = []
    folder = tempfile.mkdtemp(prefix="triwild-meshio-")
    drawings = sorted(glob.glob(os.path.join(REPO, "data", "svg", "*.svg")))
    if "--quick" in sys.argv:
        drawings = drawings[:2]
    check_groups(drawings, folder, failures)
    check_xdmf(folder, failures)
    common.finish(failures)


if __name__ == "__main__":
    main()
