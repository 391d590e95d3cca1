"""meshio: the physical groups meshio reads against the ones gmsh's API sees,
and what survives `meshio convert` to XDMF.

1. For every drawing of data/svg, meshed by default and with `cut_outside`, at
   orders 1, 2, 3, written as MSH 4.1 and 2.2, each physical group of gmsh's
   API (`getPhysicalGroups`, `getEntitiesForPhysicalGroup`, `getElements`)
   against `meshio.read`'s (elements compared by their nodes' coordinates, as
   multisets):
   - MSH 4.1: `cell_sets` (by name) hold exactly gmsh's groups (beside
     meshio's own `gmsh:bounding_entities`). The per-cell `gmsh:physical`
     holds one tag per element, so where two physical curves share an edge
     (with `cut_outside`, a shape's outline and `boundary` are one element)
     one name misses it: the script prints which;
   - MSH 2.2: meshio makes no `cell_sets`; `gmsh:physical` with `field_data`
     holds exactly gmsh's groups (2.2 writes a shared edge once per curve).
2. `meshio convert` of each order's .msh (4.1) to XDMF (needs h5py), read
   back: the cell types, and which of cell data, cell sets and names survive.

    python docs/solvers/meshio_tags.py [--quick] [--dir DIR] [--every N]
    (--quick: two drawings; --dir: every SVG below DIR instead of data/svg,
    e.g. the dev set ../shared/data/svg-dev; a drawing triwild refuses, or
    does not mesh within 120 s, is named and left out)
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
    """{cell set name: multiset of elements} of meshio's `cell_sets` (its own
    `gmsh:bounding_entities` left out)."""
    out = {}
    for name, blocks in m.cell_sets.items():
        if name.startswith("gmsh:"):
            continue
        elements = Counter()
        for block, idx in zip(m.cells, blocks):
            for row in block.data[np.asarray(idx, dtype=np.int64)]:
                elements[tuple((m.points[i, 0], m.points[i, 1]) for i in row)] += 1
        if elements:
            out[name] = elements
    return out


DIMS = {"triangle": 2, "triangle6": 2, "triangle10": 2, "line": 1, "line3": 1, "line4": 1}


def physical_groups(m) -> dict[str, Counter]:
    """{name: multiset of elements} of the per-cell `gmsh:physical` tags,
    named through `field_data`."""
    name_of = {(int(v[1]), int(v[0])): k for k, v in m.field_data.items()}
    out: dict[str, Counter] = {}
    for block, tags in zip(m.cells, m.cell_data["gmsh:physical"]):
        for row, t in zip(block.data, tags.tolist()):
            name = name_of[(DIMS[block.type], t)]
            out.setdefault(name, Counter())[tuple((m.points[i, 0], m.points[i, 1]) for i in row)] += 1
    return out


def check_groups(drawings: list[str], folder: str, failures: list[str]) -> None:
    failed_before = len(failures)
    shared_report = set()
    n = 0
    for svg in drawings:
        for cut in (False, True):
            for order in (1, 2, 3):
                try:
                    m = triwild.mesh(svg, order=order, cut_outside=cut, time_limit=120)
                except triwild.Error as e:
                    print(f"{os.path.basename(svg)}: not meshed ({type(e).__name__}: {e})")
                    continue
                for version in ("4.1", "2.2"):
                    tag = f"{os.path.basename(svg)} order {order}{' --cut-outside' if cut else ''} {version}"
                    path = os.path.join(folder, f"m{n}_{version.replace('.', '')}.msh")
                    n += 1
                    m.write(path, version=version)
                    want = gmsh_groups(path)
                    mm = meshio.read(path)
                    got = meshio_groups(mm) if version == "4.1" else physical_groups(mm)
                    for name in sorted(set(want) | set(got)):
                        if want.get(name) != got.get(name):
                            w, g = want.get(name, Counter()), got.get(name, Counter())
                            common.expect(False, f"{tag}: group {name!r}: gmsh {sum(w.values())} elements, "
                                          f"meshio {sum(g.values())}", failures)
                    if version == "4.1":
                        # gmsh:physical: one tag per element, even on a shared edge
                        per_cell = physical_groups(mm)
                        for name, elements in want.items():
                            missing = sum((elements - per_cell.get(name, Counter())).values())
                            if missing:
                                shared_report.add((name == "boundary", missing == sum(elements.values())))
                    os.remove(path)
                print(f"{os.path.basename(svg):>18} order {order}{' --cut-outside' if cut else '              '}: "
                      f"{len(want)} physical groups", flush=True)
    verdict = "are" if len(failures) == failed_before else "are NOT all"
    print(f"{n} files: meshio's groups (4.1: cell_sets, 2.2: gmsh:physical) {verdict} gmsh's, element for element")
    for is_boundary, all_missing in sorted(shared_report):
        who = "`boundary`" if is_boundary else "a shape's curve"
        print(f"  MSH 4.1 gmsh:physical misses {'all' if all_missing else 'some'} of the elements of {who} "
              "(its edges shared with another curve carry the other's tag)")


def check_xdmf(folder: str, failures: list[str]) -> None:
    print("meshio convert .msh -> .xdmf, read back:")
    for order in (1, 2, 3):
        src = os.path.join(folder, f"disk_o{order}.msh")
        common.mesh(order, 0.1).write(src)
        dst = src.replace(".msh", ".xdmf")
        meshio_cli = os.path.join(os.path.dirname(sys.executable), "meshio")
        r = subprocess.run([meshio_cli, "convert", src, dst], capture_output=True, text=True)
        if r.returncode != 0:
            print(f"  order {order}: meshio convert fails: {r.stderr.strip().splitlines()[-1]}")
            continue
        try:
            back = meshio.read(dst)
        except Exception as e:  # noqa: BLE001 - the reader's failure is the finding
            print(f"  order {order}: written, but meshio cannot read it back: {type(e).__name__}: {e}")
            print(f"    {open(dst).read().split('TopologyType=')[1].split()[0]} topology")
            continue
        types = [c.type for c in back.cells]
        data = sorted(back.cell_data)
        print(f"  order {order}: cells {types}; cell data {data}; cell sets {sorted(back.cell_sets) or 'none'}; "
              f"field data (names) {sorted(back.field_data) or 'none'}")
        orig = meshio.read(src)
        tags = lambda mesh: [  # noqa: E731 - (cell type, tag) in cell order, blocks joined
            (c.type, int(t)) for c, ts in zip(mesh.cells, mesh.cell_data.get("gmsh:physical", [])) for t in ts
        ]
        same = sorted(tags(orig)) == sorted(tags(back))
        common.expect(same, f"order {order}: gmsh:physical survives the conversion", failures)


def main() -> None:
    failures: list[str] = []
    folder = tempfile.mkdtemp(prefix="triwild-meshio-")
    root = sys.argv[sys.argv.index("--dir") + 1] if "--dir" in sys.argv else os.path.join(REPO, "data", "svg")
    drawings = sorted(glob.glob(os.path.join(root, "**", "*.svg"), recursive=True))
    if "--quick" in sys.argv:
        drawings = drawings[:2]
    if "--every" in sys.argv:  # a sample: every n-th drawing
        drawings = drawings[:: int(sys.argv[sys.argv.index("--every") + 1])]
    check_groups(drawings, folder, failures)
    check_xdmf(folder, failures)
    common.finish(failures)


if __name__ == "__main__":
    main()
