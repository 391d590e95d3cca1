#!/usr/bin/env python3
"""Check that meshio reads triwild's cell tags (issue 7: "meshio reads the cell
tags of the 2.2 and 4.1 outputs").

For every sidecar `<file>.msh.json` under the given directories (written by
tests/regions_meshio.rs), read `<file>.msh` with meshio and check:
- every triangle and line cell block carries "gmsh:physical", one positive tag
  per cell;
- the physical names meshio reports (field_data: name -> [tag, dim]) are exactly
  the sidecar's groups;
- the number of triangles (and lines) per physical group equals the sidecar's,
  and the node, triangle and line totals too. In MSH 4.1 an edge on several
  physical curves is one line cell whose entity they all list: meshio's
  "gmsh:physical" holds the first of them, so lines per group are counted
  from meshio's cell_sets there, and the line total is the sidecar's
  "distinct_lines".

Prints one line per failing mesh and ends with "meshio: N passed, M failed".
Exit status 0 iff nothing failed and at least one sidecar was found.
"""

import json
import sys
from collections import Counter
from pathlib import Path

import meshio


def check(sidecar: Path) -> list[str]:
    """Every problem meshio shows with the mesh of `sidecar` (empty: all good)."""
    spec = json.loads(sidecar.read_text())
    msh = sidecar.with_name(spec["msh"])
    try:
        mesh = meshio.read(msh, file_format="gmsh")
    except Exception as e:  # noqa: BLE001 - any reader failure is the finding
        return [f"meshio cannot read it: {type(e).__name__}: {e}"]
    problems = []

    groups = spec["groups"]
    expected_fields = {g["name"]: (g["tag"], g["dim"]) for g in groups}
    if len(expected_fields) < len(groups):
        names = Counter(g["name"] for g in groups)
        dup = sorted(n for n, c in names.items() if c > 1)
        problems.append(
            f"names shared by several physical groups {dup}: meshio's field_data "
            f"keeps one (tag, dim) per name"
        )
    got_fields = {
        str(name): (int(v[0]), int(v[1])) for name, v in mesh.field_data.items()
    }
    if got_fields != expected_fields:
        missing = {k: v for k, v in expected_fields.items() if got_fields.get(k) != v}
        extra = {k: v for k, v in got_fields.items() if expected_fields.get(k) != v}
        problems.append(f"field_data differs: expected {missing}, meshio has {extra}")

    physical = mesh.cell_data.get("gmsh:physical")
    if physical is None:
        return problems + ["no gmsh:physical cell data"]
    counts = {1: Counter(), 2: Counter()}
    totals = {1: 0, 2: 0}
    for block, tags in zip(mesh.cells, physical):
        if block.type.startswith("triangle"):
            dim = 2
        elif block.type.startswith("line"):
            dim = 1
        else:
            problems.append(f"unexpected cell block {block.type}")
            continue
        if tags is None or len(tags) != len(block.data):
            problems.append(f"{block.type} block of {len(block.data)} cells without one tag each")
            continue
        if any(int(t) <= 0 for t in tags):
            problems.append(f"{block.type} block has cells with no physical tag")
        totals[dim] += len(block.data)
        counts[dim].update(int(t) for t in tags)

    shared = spec["version"].startswith("v41")
    if shared:
        # lines per group from the cell sets (every physical curve of an entity)
        counts[1] = Counter()
        for name, blocks in mesh.cell_sets.items():
            if name not in mesh.field_data:
                continue  # meshio's own sets (gmsh:bounding_entities)
            tag, dim = mesh.field_data[name][0], mesh.field_data[name][1]
            if dim != 1:
                continue
            for block, ids in zip(mesh.cells, blocks):
                if block.type.startswith("line") and ids is not None and len(ids) > 0:
                    counts[1][int(tag)] += len(ids)
    for dim, key in ((2, "triangles"), (1, "lines")):
        want = spec["distinct_lines"] if shared and dim == 1 else spec[key]
        if totals[dim] != want:
            problems.append(f"{totals[dim]} {key}, expected {want}")
        expected = Counter({g["tag"]: g["elements"] for g in groups if g["dim"] == dim})
        if counts[dim] != expected:
            problems.append(
                f"{key} per physical tag {dict(counts[dim])}, expected {dict(expected)}"
            )
    if len(mesh.points) != spec["nodes"]:
        problems.append(f"{len(mesh.points)} nodes, expected {spec['nodes']}")
    return problems


def main(argv: list[str]) -> int:
    roots = [Path(a) for a in argv[1:]] or [Path("target/test-out")]
    sidecars = sorted(p for r in roots for p in r.rglob("*.msh.json"))
    failed = 0
    for s in sidecars:
        problems = check(s)
        if problems:
            failed += 1
            print(f"FAILED: {s.with_suffix('')}")
            for p in problems:
                print(f"  {p}")
    if not sidecars:
        print(f"no *.msh.json sidecars under {[str(r) for r in roots]}", file=sys.stderr)
    print(f"meshio: {len(sidecars) - failed} passed, {failed} failed")
    return 0 if sidecars and failed == 0 else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
