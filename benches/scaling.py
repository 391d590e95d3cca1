#!/usr/bin/env python3
"""Scaling of `triwild` in the input size.

Generates SVG soups, runs the release binary on each with default flags and
`--stats`, and prints wall time against input segments with the least-squares
exponent of time ~ segments^k on the soups. Python 3 standard library only.

    cargo build --release --locked
    python3 benches/scaling.py [--bin target/release/triwild] [--sizes 1000,3000,...]
        [--cases soup,zigzag,serpentine,duplicates] [--keep DIR] [--time-limit S]

Inputs (fixed seeds, all in a 1000 x 1000 viewBox, thin strokes: narrower than
l_m, so each stroke is its centre line, a feature without a region):

- soup N: N separate paths, half straight segments, half cubics, random
  position and direction, each about 3000/sqrt(N) long (so a piece crosses a
  few others at every N and the output grows linearly);
- zigzag N: one polyline of N segments, x advancing by 1000/N, y alternating
  0 / 100 (its teeth are far closer than mu: all secondary, simplified);
- serpentine N: one polyline of N segments in about sqrt(N) rows, every
  segment longer than mu (all primary);
- duplicates: one filled path (a cubic blob) repeated 3000 times, the same
  paint, plus 3000 copies of a stroked curve.

Further series have strokes meshed as areas (wide enough to be kept apart:
the paint model's default), and every row reports the memory:

- hatch N: N parallel stroked lines across the box, spacing 900/N, width a
  quarter of the spacing;
- stroked-path N: the serpentine's one polyline of N segments, stroked at a
  quarter of its row gap;
- stroked-soup N: the soup's straight segments (N of them), stroked at a
  width of 1 (they cross and overlap as in the fuzz findings' soups);
- shapes N (sizes from --shape-sizes): N filled circles with a stroke of
  another colour, on a square grid;
- stroked-circles N (sizes from --shape-sizes): N unfilled circles at random
  places, radius 1 to 8, stroke width 0.6 (the "5 000 stroked
  circles" of benches/README.md: they overlap and cross, and each stroke is an area).

Each row gives wall and CPU time, the stages' times, triangles, and the peak
resident memory the run reports (`peak_memory_mb`); each series ends with the
least-squares exponents of wall time, CPU time and memory against its size.
"""

import argparse
import json
import math
import os
import random
import resource
import subprocess
import sys
import tempfile
import time

HEAD = '<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 1000 1000">\n'
STROKE = 'fill="none" stroke="#000" stroke-width="0.01"'


def random_segment(rnd, ln):
    """A segment of length about `ln` (clipped to the box) at a random place
    and direction."""
    x, y = rnd.uniform(50, 950), rnd.uniform(50, 950)
    a = rnd.uniform(0, 2 * math.pi)
    x1 = min(max(x + ln * math.cos(a), 0), 1000)
    y1 = min(max(y + ln * math.sin(a), 0), 1000)
    return x, y, x1, y1


def soup(n, seed=1):
    rnd = random.Random(seed)
    ln = 3000.0 / math.sqrt(n)
    out = [HEAD]
    for k in range(n):
        x, y, x1, y1 = random_segment(rnd, ln)
        if k % 2 == 0:
            d = f"M{x:.4f} {y:.4f}L{x1:.4f} {y1:.4f}"
        else:
            # a gentle bend: control points off the chord by a fifth of its length
            nx, ny = -(y1 - y) * 0.2, (x1 - x) * 0.2
            d = (
                f"M{x:.4f} {y:.4f}C{x + (x1 - x) / 3 + nx:.4f} {y + (y1 - y) / 3 + ny:.4f} "
                f"{x + 2 * (x1 - x) / 3 + nx:.4f} {y + 2 * (y1 - y) / 3 + ny:.4f} {x1:.4f} {y1:.4f}"
            )
        out.append(f'<path {STROKE} d="{d}"/>\n')
    out.append("</svg>\n")
    return "".join(out)


def zigzag(n):
    pts = [f"{1000.0 * k / n:.6f} {0 if k % 2 == 0 else 100}" for k in range(n + 1)]
    return HEAD + f'<path {STROKE} d="M{"L".join(pts)}"/>\n</svg>\n'


def serpentine(n):
    rows = max(1, int(math.sqrt(n / 2)))
    per_row = max(1, n // rows)
    pts = []
    for r in range(rows):
        y0 = 50 + 900.0 * r / rows
        h = 0.6 * 900.0 / rows
        xs = range(per_row + 1) if r % 2 == 0 else range(per_row, -1, -1)
        for k in xs:
            x = 50 + 900.0 * k / per_row
            pts.append(f"{x:.6f} {y0 + (h if k % 2 else 0):.6f}")
    return HEAD + f'<path {STROKE} d="M{"L".join(pts)}"/>\n</svg>\n'


def hatch(n):
    gap = 900.0 / n
    out = [HEAD]
    for k in range(n):
        y = 50 + gap * (k + 0.5)
        out.append(
            f'<path fill="none" stroke="#000" stroke-width="{gap / 4:.6g}" d="M50 {y:.6f}H950"/>\n'
        )
    out.append("</svg>\n")
    return "".join(out)


def stroked_path(n):
    rows = max(1, int(math.sqrt(n / 2)))
    width = 0.25 * 0.4 * 900.0 / rows
    text = serpentine(n)
    return text.replace(STROKE, f'fill="none" stroke="#000" stroke-width="{width:.6g}"')


def stroked_soup(n, seed=1):
    rnd = random.Random(seed)
    ln = 3000.0 / math.sqrt(n)
    out = [HEAD]
    for _ in range(n):
        x, y, x1, y1 = random_segment(rnd, ln)
        out.append(f'<path fill="none" stroke="#000" stroke-width="1" d="M{x:.4f} {y:.4f}L{x1:.4f} {y1:.4f}"/>\n')
    out.append("</svg>\n")
    return "".join(out)


def shapes(n):
    side = max(1, math.ceil(math.sqrt(n)))
    cell = 900.0 / side
    out = [HEAD]
    for k in range(n):
        cx, cy = 50 + cell * (k % side + 0.5), 50 + cell * (k // side + 0.5)
        out.append(
            f'<circle cx="{cx:.6f}" cy="{cy:.6f}" r="{0.35 * cell:.6f}" fill="#3366cc" '
            f'stroke="#cc3333" stroke-width="{0.05 * cell:.6f}"/>\n'
        )
    out.append("</svg>\n")
    return "".join(out)


def stroked_circles(n, seed=1):
    rnd = random.Random(seed)
    out = [HEAD]
    for _ in range(n):
        cx, cy, r = rnd.uniform(20, 980), rnd.uniform(20, 980), rnd.uniform(1, 8)
        out.append(
            f'<circle cx="{cx:.4f}" cy="{cy:.4f}" r="{r:.4f}" fill="none" '
            'stroke="#000" stroke-width="0.6"/>\n'
        )
    out.append("</svg>\n")
    return "".join(out)


def duplicates(copies=3000):
    blob = "M300 300C400 200 600 200 700 300C800 400 800 600 700 700C600 800 400 800 300 700Z"
    curve = "M100 900C300 800 700 950 900 850"
    out = [HEAD]
    out += [f'<path fill="#336699" d="{blob}"/>\n' for _ in range(copies)]
    out += [f'<path {STROKE} d="{curve}"/>\n' for _ in range(copies)]
    out.append("</svg>\n")
    return "".join(out)


def run(binary, svg_text, name, keep, time_limit):
    d = keep or tempfile.mkdtemp(prefix="triwild-scaling-")
    src = os.path.join(d, name + ".svg")
    with open(src, "w") as f:
        f.write(svg_text)
    cmd = [binary, src, "-o", os.path.join(d, name + ".msh"), "--stats", "-q"]
    cmd += ["--time-limit", str(time_limit)]
    t0 = time.monotonic()
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    p = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.monotonic() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    stats = {}
    if p.returncode == 0:
        try:
            stats = json.loads(p.stdout)
        except json.JSONDecodeError:
            pass
    return p.returncode, wall, cpu, stats


def exponent(rows):
    pts = [(math.log(n), math.log(t)) for n, t in rows if t > 0]
    if len(pts) < 2:
        return float("nan")
    mx = sum(x for x, _ in pts) / len(pts)
    my = sum(y for _, y in pts) / len(pts)
    sxx = sum((x - mx) ** 2 for x, _ in pts)
    sxy = sum((x - mx) * (y - my) for x, y in pts)
    return sxy / sxx


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bin", default="target/release/triwild")
    ap.add_argument("--sizes", default="1000,3000,10000,30000,100000")
    ap.add_argument("--shape-sizes", default="100,300,1000,3000,10000")
    ap.add_argument(
        "--cases",
        default="soup,zigzag,serpentine,duplicates,hatch,stroked-path,stroked-soup,shapes,"
        "stroked-circles",
    )
    ap.add_argument("--keep", help="directory to keep the inputs and meshes in")
    ap.add_argument("--time-limit", default="600")
    a = ap.parse_args()
    sizes = [int(s) for s in a.sizes.split(",")]
    shape_sizes = [int(s) for s in a.shape_sizes.split(",")]
    cases = a.cases.split(",")
    if a.keep:
        os.makedirs(a.keep, exist_ok=True)
    gens = {
        "soup": soup,
        "zigzag": zigzag,
        "serpentine": serpentine,
        "hatch": hatch,
        "stroked-path": stroked_path,
        "stroked-soup": stroked_soup,
        "shapes": shapes,
        "stroked-circles": stroked_circles,
    }
    stages = ["load", "features", "bsp", "optimize", "curve", "regions"]
    print(
        "| input | size | segments | exit | wall s | cpu s | "
        + " | ".join(f"{k} s" for k in stages)
        + " | triangles | peak MB | merged dups |"
    )
    print("|---|---|---|---|---|---|" + "---|" * len(stages) + "---|---|---|")
    series = {}
    todo = [
        (c, n) for c in cases if c in gens for n in (shape_sizes if c in ("shapes", "stroked-circles") else sizes)
    ]
    if "duplicates" in cases:
        todo.append(("duplicates", 3000))
    for case, n in todo:
        text = duplicates(n) if case == "duplicates" else gens[case](n)
        name = f"{case}-{n}"
        code, wall, cpu, st = run(a.bin, text, name, a.keep, a.time_limit)
        inp = st.get("input", {})
        segs = inp.get("lines", 0) + inp.get("cubics", 0) + inp.get("conics", 0)
        times = st.get("times", {})
        tris = st.get("output", {}).get("triangles", "")
        peak = st.get("peak_memory_mb")
        merged = inp.get("paint", {}).get("duplicates_merged", "")
        f = lambda k: f"{times[k]:.2f}" if k in times else ""
        print(
            f"| {case} | {n} | {segs or ''} | {code} | {wall:.2f} | {cpu:.2f} | "
            + " | ".join(f(k) for k in stages)
            + f" | {tris} | {'' if peak is None else round(peak)} | {merged} |",
            flush=True,
        )
        if code == 0 and case != "duplicates":
            series.setdefault(case, []).append((n, wall, cpu, peak))
    for case, rows in series.items():
        k_wall = exponent([(n, w) for n, w, _, _ in rows])
        k_cpu = exponent([(n, c) for n, _, c, _ in rows])
        k_mem = exponent([(n, m) for n, _, _, m in rows if m])
        print(
            f"exponent ({case}, {rows[0][0]}..{rows[-1][0]}): "
            f"wall {k_wall:.2f}, cpu {k_cpu:.2f}, memory {k_mem:.2f}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
