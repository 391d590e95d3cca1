#!/usr/bin/env python3
"""triwild against gmsh on the L-shaped domain, the FEM user's first mesh.

The domain is the unit L, [0,2]² minus [1,2]² (six straight segments, one
region), drawn as one filled SVG path (output coordinates: y up). Three cases:

- ``u20k`` and ``u120k``: a uniform size giving about 20 000 and 120 000
  triangles, ``--cut-outside --order 1``;
- ``p3``: cubic elements (``--order 3``) graded toward the re-entrant corner
  (1, 1): h = min(l, h0 + g·r), r the distance to the corner, the same formula
  as ``--size-expr`` for triwild and as a MathEval background field for gmsh.

triwild runs as a subprocess at one thread with ``--stats`` (its wall time,
and the stage times of its JSON); gmsh runs in this process through its Python
API, one thread (``General.NumThreads = 1``), timing ``generate(2)`` (and
``setOrder(3)`` for p3, which on straight sides only adds nodes). gmsh's size
is calibrated to the triangle count triwild gives (a few quick gmsh runs, not
timed), so the two meshes have about the same number of triangles. Triangle
counts and minimum angles are computed here from each mesh's corner nodes.

Needs gmsh and numpy (``python3 -m venv /tmp/gmsh-venv &&
/tmp/gmsh-venv/bin/pip install gmsh numpy``, or the venv of
``../shared/bench/setup.sh``):

    /tmp/gmsh-venv/bin/python benches/gmsh_lshape.py --bin target/release/triwild
    ... --cases u20k,p3 --reps 3 --json out.json

Prints one row per case: both wall times, the ratio triwild / gmsh, triangle
counts, minimum angles, and triwild's stage times.
"""

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

L_SVG = """<svg xmlns="http://www.w3.org/2000/svg" viewBox="-0.5 -2.5 3 3">
<path id="L" d="M0,0 H2 V-1 H1 V-2 H0 Z" fill="black"/>
</svg>
"""

# The L in output coordinates (counter-clockwise), and its re-entrant corner.
L_POINTS = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]
CORNER = (1.0, 1.0)

# The graded case: h = min(l, h0 + g·r), about 7 700 cubic triangles.
GRADED = {"l": 0.1, "h0": 0.0015, "g": 0.07}

# name: (triwild's edge length, order, graded); the uniform lengths give about
# 20 000 and 120 000 triangles in the L.
CASES = {
    "u20k": (0.0186, 1, False),
    "u120k": (0.0076, 1, False),
    "p3": (GRADED["l"], 3, True),
}


def graded_expr(scale=1.0):
    """The graded size as a formula in x and y (both tools parse this)."""
    h0, g = GRADED["h0"] * scale, GRADED["g"] * scale
    cx, cy = CORNER
    return f"{h0} + {g}*sqrt((x-{cx})^2 + (y-{cy})^2)"


def min_angle_deg(xy, tris):
    """The smallest corner angle (degrees) of the triangles `tris` (n × 3
    indices into the n × 2 array `xy`)."""
    a, b, c = xy[tris[:, 0]], xy[tris[:, 1]], xy[tris[:, 2]]
    worst = 180.0
    for p, q, r in ((a, b, c), (b, c, a), (c, a, b)):
        u, v = q - p, r - p
        cos = np.einsum("ij,ij->i", u, v) / (
            np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1)
        )
        worst = min(worst, float(np.degrees(np.arccos(np.clip(cos, -1, 1))).min()))
    return worst


def current_mesh_triangles(gmsh):
    """The corner nodes of every triangle of gmsh's current model (any order)."""
    tags, coords, _ = gmsh.model.mesh.getNodes()
    index = np.zeros(int(tags.max()) + 1, dtype=np.int64)
    index[tags.astype(np.int64)] = np.arange(len(tags))
    xy = coords.reshape(-1, 3)[:, :2]
    tris = []
    types, _, nodes = gmsh.model.mesh.getElements(2)
    for t, n in zip(types, nodes):
        name, dim, order, nn, _, _ = gmsh.model.mesh.getElementProperties(t)
        if dim != 2 or not name.lower().startswith("triangle"):
            continue
        tris.append(index[n.astype(np.int64).reshape(-1, nn)[:, :3]])
    tris = np.concatenate(tris) if tris else np.zeros((0, 3), dtype=np.int64)
    return xy, tris


def read_msh(gmsh, path):
    """Triangle count and minimum angle of a .msh file."""
    gmsh.clear()
    gmsh.open(path)
    xy, tris = current_mesh_triangles(gmsh)
    gmsh.clear()
    return len(tris), min_angle_deg(xy, tris)


def run_triwild(binary, svg, out, case):
    l, order, graded = CASES[case]
    cmd = [
        binary,
        svg,
        "-o",
        out,
        "--cut-outside",
        "--order",
        str(order),
        "--edge-length-abs",
        str(l),
        "--threads",
        "1",
        "--stats",
        "--quiet",
    ]
    if graded:
        cmd += ["--size-expr", graded_expr()]
    t = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t
    if p.returncode != 0:
        sys.exit(f"triwild failed ({p.returncode}): {' '.join(cmd)}\n{p.stderr}")
    stats = json.loads(p.stdout.strip().splitlines()[-1])
    return wall, stats


def gmsh_model(gmsh, size, graded):
    """The L in gmsh's built-in kernel with a uniform size `size`, or the graded
    field scaled by `size` (1 = the formula as triwild takes it)."""
    gmsh.clear()
    gmsh.model.add("L")
    geo = gmsh.model.geo
    pts = [geo.addPoint(x, y, 0) for x, y in L_POINTS]
    lines = [geo.addLine(pts[i], pts[(i + 1) % len(pts)]) for i in range(len(pts))]
    loop = geo.addCurveLoop(lines)
    geo.addPlaneSurface([loop])
    geo.synchronize()
    opt = gmsh.option.setNumber
    # (options outlive the model: every case sets all of them)
    if graded:
        f = gmsh.model.mesh.field.add("MathEval")
        gmsh.model.mesh.field.setString(
            f, "F", f"min({GRADED['l'] * size}, {graded_expr(size)})"
        )
        gmsh.model.mesh.field.setAsBackgroundMesh(f)
        opt("Mesh.MeshSizeMin", 0)
        opt("Mesh.MeshSizeMax", 1e22)
        opt("Mesh.MeshSizeExtendFromBoundary", 0)
        opt("Mesh.MeshSizeFromPoints", 0)
        opt("Mesh.MeshSizeFromCurvature", 0)
    else:
        opt("Mesh.MeshSizeMin", size)
        opt("Mesh.MeshSizeMax", size)
        opt("Mesh.MeshSizeExtendFromBoundary", 1)
        opt("Mesh.MeshSizeFromPoints", 1)


def run_gmsh(gmsh, size, graded, order):
    """gmsh's wall time for `generate(2)` (and `setOrder`), triangles, angle."""
    gmsh_model(gmsh, size, graded)
    t = time.perf_counter()
    gmsh.model.mesh.generate(2)
    gen = time.perf_counter() - t
    if order > 1:
        gmsh.model.mesh.setOrder(order)
    total = time.perf_counter() - t
    xy, tris = current_mesh_triangles(gmsh)
    return gen, total, len(tris), min_angle_deg(xy, tris)


def calibrate_gmsh(gmsh, case, target):
    """gmsh's size (uniform) or field scale (graded) giving about `target`
    triangles: the count goes as 1/size², so a few rescaled runs."""
    l, order, graded = CASES[case]
    size = 1.0 if graded else l
    for _ in range(4):
        gmsh_model(gmsh, size, graded)
        gmsh.model.mesh.generate(2)
        _, tris = current_mesh_triangles(gmsh)
        n = len(tris)
        if abs(n - target) <= 0.01 * target:
            break
        size *= math.sqrt(n / target)
    return size


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bin", default="target/release/triwild")
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--reps", type=int, default=1, help="best of N for both tools")
    ap.add_argument("--json", help="also write the rows here")
    args = ap.parse_args()
    import gmsh

    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.option.setNumber("General.NumThreads", 1)
    gmsh.option.setNumber("Mesh.MaxNumThreads2D", 1)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        svg = os.path.join(tmp, "L.svg")
        with open(svg, "w") as f:
            f.write(L_SVG)
        for case in args.cases.split(","):
            l, order, graded = CASES[case]
            out = os.path.join(tmp, f"{case}.msh")
            best = None
            for _ in range(args.reps):
                wall, stats = run_triwild(args.bin, svg, out, case)
                if best is None or wall < best[0]:
                    best = (wall, stats)
            wall, stats = best
            tri_n, tri_angle = read_msh(gmsh, out)
            size = calibrate_gmsh(gmsh, case, tri_n)
            g = min(
                (run_gmsh(gmsh, size, graded, order) for _ in range(args.reps)),
                key=lambda r: r[1],
            )
            times = stats.get("times", {})
            row = {
                "case": case,
                "triwild_s": round(wall, 3),
                "gmsh_s": round(g[1], 3),
                "gmsh_generate_s": round(g[0], 3),
                "ratio": round(wall / g[1], 2),
                "triwild_triangles": tri_n,
                "gmsh_triangles": g[2],
                "triwild_min_angle": round(tri_angle, 2),
                "gmsh_min_angle": round(g[3], 2),
                "triwild_times": {
                    k: round(v, 3) for k, v in times.items() if isinstance(v, float)
                },
                "triwild_bsp_vertices": (stats.get("bsp") or {}).get("vertices"),
                "triwild_output_nodes": (stats.get("output") or {}).get("nodes"),
                "gmsh_size": size,
            }
            rows.append(row)
            print(
                f"{case:6} triwild {wall:7.2f} s  gmsh {g[1]:6.2f} s  ratio {row['ratio']:5.2f}  "
                f"triangles {tri_n:7d} / {g[2]:7d}  min angle {tri_angle:5.2f}° / {g[3]:5.2f}°",
                flush=True,
            )
            print(
                "       triwild stages: "
                + ", ".join(f"{k} {v}" for k, v in row["triwild_times"].items())
                + f"; BSP vertices {row['triwild_bsp_vertices']}",
                flush=True,
            )
    gmsh.finalize()
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=1)


if __name__ == "__main__":
    main()
