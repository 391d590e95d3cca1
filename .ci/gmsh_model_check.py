#!/usr/bin/env python3
"""Check that gmsh's own API sees triwild's meshes as a model a solver can use
(issue 15).

For every .msh file under the given directories (default: target/test-out/
gmsh_model, where tests/gmsh_model.rs writes its meshes), open it with gmsh
and check (MSH 2.2 files with gmsh's Mesh.CreateTopologyMsh2 set, as the
format has no entities of its own):
- every surface entity has elements, nodes (gmsh.model.mesh.getNodes(2,
  tag), its boundary's included: a surface of a few triangles may have all
  its nodes on its curves) and bounding curves (gmsh.model.getBoundary);
- a physical curve named "boundary" exists and its line elements run with
  the domain on their left: the area they enclose (sum over their chords of
  (x_a y_b - x_b y_a) / 2) equals the area of the straight triangles on the
  elements' corners, which is positive;
- within each piece of a physical curve (its elements on one curve entity)
  no two line elements start at the same node and no two end at the same
  node, except where the piece meets itself (a self-crossing outline, a
  branch): there as many start as end (one more of either when an odd number
  meet);
- (MSH 4.1) no two line elements join the same two nodes: an edge on several
  physical curves is one element in one entity they all list (issue 39);
- (MSH 4.1) gmsh's own mesh operations accept the model:
  gmsh.model.mesh.refine(), then gmsh.model.mesh.setOrder(2) (they fail, for
  example, on "mesh edges from different curves share nodes"; MSH 2.2 gives an
  element one physical tag, so an edge on two physical curves is two elements
  there, and these are not asked of it).

Prints one line per failing mesh and ends with "gmsh model: N passed, M failed".
Exit status 0 iff nothing failed and at least one mesh was found.
"""

import sys
from collections import Counter
from pathlib import Path

import gmsh
import numpy as np

# Relative tolerance of the area comparison (the two sums add the same
# corner coordinates in different orders).
AREA_RTOL = 1e-9


def elements_of_group(dim: int, tag: int) -> list[tuple[int, np.ndarray]]:
    """(element type, node tags as rows) of every element block of a physical group."""
    out = []
    for ent in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
        types, _, nodes = gmsh.model.mesh.getElements(dim, ent)
        for t, n in zip(types, nodes):
            _, _, _, count, _, _ = gmsh.model.mesh.getElementProperties(t)
            out.append((t, np.asarray(n, dtype=np.int64).reshape(-1, count)))
    return out


def check(path: Path) -> list[str]:
    """Every problem gmsh's API shows with the model in `path` (empty: all good)."""
    problems = []
    gmsh.clear()
    # MSH 2.2 has no $Entities: gmsh rebuilds the topology from the elements'
    # elementary tags when asked to (the README tells users the same).
    with open(path, "rb") as f:
        f.readline()
        legacy = f.readline().split()[:1] == [b"2.2"]
    gmsh.option.setNumber("Mesh.CreateTopologyMsh2", 1 if legacy else 0)
    try:
        gmsh.open(str(path))
    except Exception as e:  # noqa: BLE001 - any reader failure is the finding
        return [f"gmsh cannot open it: {e}"]

    surfaces = gmsh.model.getEntities(2)
    if not surfaces:
        problems.append("no surface entity")
    for _, tag in surfaces:
        # A surface of a few triangles may have every node on its bounding
        # curves, where gmsh classifies them (on the curve entities), so its
        # nodes are asked for with its boundary's; it must have elements too.
        nodes, _, _ = gmsh.model.mesh.getNodes(2, tag, includeBoundary=True)
        if len(nodes) == 0:
            problems.append(f"surface {tag}: getNodes(2, {tag}) returns no node")
        if not any(len(e) for e in gmsh.model.mesh.getElements(2, tag)[1]):
            problems.append(f"surface {tag}: getElements(2, {tag}) returns no element")
        bound = gmsh.model.getBoundary([(2, tag)], combined=False, oriented=False)
        if not bound:
            problems.append(f"surface {tag}: getBoundary gives no curve")

    tags, coords, _ = gmsh.model.mesh.getNodes()
    xy = dict(zip(tags.tolist(), coords.reshape(-1, 3)[:, :2]))

    # The domain's straight-sided area: corner triangles of every 2D element.
    domain_area = 0.0
    for _, tag in surfaces:
        types, _, nodes = gmsh.model.mesh.getElements(2, tag)
        for t, n in zip(types, nodes):
            _, _, _, count, _, _ = gmsh.model.mesh.getElementProperties(t)
            for row in np.asarray(n, dtype=np.int64).reshape(-1, count):
                a, b, c = (xy[int(v)] for v in row[:3])
                domain_area += 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))

    names = {}
    for dim, tag in gmsh.model.getPhysicalGroups(1):
        names[gmsh.model.getPhysicalName(dim, tag)] = tag
        name = gmsh.model.getPhysicalName(dim, tag)
        for ent in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
            starts, ends = Counter(), Counter()
            types, _, nodes = gmsh.model.mesh.getElements(dim, ent)
            for t, n in zip(types, nodes):
                _, _, _, count, _, _ = gmsh.model.mesh.getElementProperties(t)
                rows = np.asarray(n, dtype=np.int64).reshape(-1, count)
                starts.update(rows[:, 0].tolist())
                ends.update(rows[:, 1].tolist())
            # Where the piece meets itself (a crossing, a branch) `degree` > 2
            # elements meet: as many start as end there (one more for odd degree).
            bad = []
            for v in set(starts) | set(ends):
                s, e = starts[v], ends[v]
                degree = s + e
                if (degree <= 2 and (s > 1 or e > 1)) or abs(s - e) > degree % 2:
                    bad.append(v)
            if bad:
                problems.append(
                    f"physical curve {name!r}, entity {ent}: {len(bad)} nodes where line "
                    f"elements do not run one way (two start or two end there)"
                )

    if not legacy:
        seen, twice = {}, []
        for _, ent in gmsh.model.getEntities(1):
            types, _, nodes = gmsh.model.mesh.getElements(1, ent)
            for t, n in zip(types, nodes):
                _, _, _, count, _, _ = gmsh.model.mesh.getElementProperties(t)
                for row in np.asarray(n, dtype=np.int64).reshape(-1, count):
                    key = (int(min(row[0], row[1])), int(max(row[0], row[1])))
                    if key in seen:
                        twice.append((seen[key], ent, key))
                    seen[key] = ent
        if twice:
            a, b, (u, v) = twice[0]
            problems.append(
                f"{len(twice)} edges joined by two line elements (first: nodes {u} and {v}, "
                f"on curves {a} and {b})"
            )

    if "boundary" not in names:
        problems.append("no physical curve 'boundary'")
    else:
        enclosed = 0.0
        for _, rows in elements_of_group(1, names["boundary"]):
            for row in rows:
                a, b = xy[int(row[0])], xy[int(row[1])]
                enclosed += 0.5 * (a[0] * b[1] - b[0] * a[1])
        if not (domain_area > 0 and abs(enclosed - domain_area) <= AREA_RTOL * domain_area):
            problems.append(
                f"'boundary' encloses {enclosed!r}, the domain's corner triangles cover "
                f"{domain_area!r}: not counter-clockwise around the domain"
            )

    # gmsh's own operations on the mesh (last: they change the model).
    for what, op in () if legacy else (
        ("refine()", gmsh.model.mesh.refine),
        ("setOrder(2)", lambda: gmsh.model.mesh.setOrder(2)),
    ):
        gmsh.logger.start()
        try:
            op()
            errors = [m for m in gmsh.logger.get() if m.startswith("Error")]
        except Exception as e:  # noqa: BLE001 - any failure is the finding
            errors = [str(e)]
        finally:
            gmsh.logger.stop()
        if errors:
            problems.append(f"gmsh.model.mesh.{what} fails: {errors[0]}")
            break
    return problems


def main(argv: list[str]) -> int:
    roots = [Path(a) for a in argv[1:]] or [Path("target/test-out/gmsh_model")]
    meshes = sorted(p for r in roots for p in ([r] if r.is_file() else r.rglob("*.msh")))
    gmsh.initialize(["-noenv"], readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)
    failed = 0
    try:
        for m in meshes:
            problems = check(m)
            if problems:
                failed += 1
                print(f"FAILED: {m}")
                for p in problems:
                    print(f"  {p}")
    finally:
        gmsh.finalize()
    if not meshes:
        print(f"no .msh files under {[str(r) for r in roots]}", file=sys.stderr)
    print(f"gmsh model: {len(meshes) - failed} passed, {failed} failed")
    return 0 if meshes and failed == 0 else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
