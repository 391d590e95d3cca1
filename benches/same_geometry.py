#!/usr/bin/env python3
"""The reference comparison on the geometry triwild meshes.

With its paint model, triwild meshes what a drawing paints: a
stroke is the area it covers (two outlines where the reference meshes one
centre line), clipped shapes end at their clip, invisible shapes are gone. On
such drawings `compare.py` compares two meshers on different inputs. This
script writes, for every drawing whose geometry the paint model changed, an
SVG of the curves triwild meshes (its feature set: primary sections as cubic
pieces chained along their curves, secondary polylines as lines; no fill, no
stroke width), so the reference can mesh the same curves:

    PY=/tmp/bench-venv/bin/python
    $PY benches/same_geometry.py --bin target/release/triwild --out-dir /tmp/sg FILES...
    # -> /tmp/sg/<stem>.svg for the changed drawings, /tmp/sg/map.tsv (original -> exported)
    $PY ../shared/bench/compare.py $(cut -f2 /tmp/sg/map.tsv) --tools ref --jobs 1 --cpus 1 --out /tmp/sg-ref.csv
    $PY benches/same_geometry.py --merge ORIGINAL.csv /tmp/sg-ref.csv /tmp/sg/map.tsv --out SAME.csv
    $PY ../shared/bench/judge.py SAME.csv

`--merge` takes a compare.py CSV of both tools on the original drawings and
replaces the reference's rows of the changed drawings by its rows on their
exported geometry (keyed by the original path), so judge.py pairs them.

A drawing counts as changed when `--stats` (at `--stop-after bsp`, cheap)
reports a stroke meshed as an area, a clipped or masked shape, a shape dropped
as invisible or decoration, or a trimmed outline piece. Coordinates are
written with y pointing down again (triwild's features have y up).
"""

import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile

PAINT_KEYS = ("strokes_as_areas", "clipped_shapes", "masked_shapes", "dropped_invisible",
              "dropped_decoration")


def changed_by_paint(binary, svg):
    """Whether the paint model changed what `svg` meshes (see the module doc)."""
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "x.msh")
        run = subprocess.run([binary, svg, "-o", out, "--stop-after", "bsp", "--stats"],
                             capture_output=True, text=True)
    if run.returncode != 0:
        return False
    stats = json.loads(run.stdout.strip().splitlines()[-1])
    paint = stats.get("input", {}).get("paint", {})
    trimmed = stats.get("features", {}).get("trimmed_pieces", 0) or 0
    return any((paint.get(k) or 0) > 0 for k in PAINT_KEYS) or trimmed > 0


def fmt(p):
    return "%.17g,%.17g" % (p[0], -p[1])


def feature_svg(features):
    """An SVG of the feature set's curves (stroked hairlines, no fill)."""
    primary = features["primary"]
    paths = []
    seen = [False] * len(primary)

    def chain_from(i):
        d = ["M" + fmt(primary[i]["ctrl"][0])]
        j = i
        while j is not None and not seen[j]:
            seen[j] = True
            c = primary[j]["ctrl"]
            if len(c) == 2:
                d.append("L" + fmt(c[1]))
            elif len(c) == 3:
                d.append("Q" + " ".join(fmt(p) for p in c[1:]))
            else:
                d.append("C" + " ".join(fmt(p) for p in c[1:4]))
            j = primary[j].get("next")
        return " ".join(d)

    # Open chains from their first section, then the closed loops left.
    for i, s in enumerate(primary):
        if s.get("prev") is None and not seen[i]:
            paths.append(chain_from(i))
    for i in range(len(primary)):
        if not seen[i]:
            paths.append(chain_from(i))
    for poly in features["secondary"]:
        pts = poly["points"]
        if len(pts) >= 2:
            paths.append("M" + fmt(pts[0]) + " " + " ".join("L" + fmt(p) for p in pts[1:]))
    xs, ys = [], []
    for s in primary:
        for p in s["ctrl"]:
            xs.append(p[0])
            ys.append(-p[1])
    for poly in features["secondary"]:
        for p in poly["points"]:
            xs.append(p[0])
            ys.append(-p[1])
    if not xs:
        xs, ys = [0.0, 1.0], [0.0, 1.0]
    x0, y0 = min(xs), min(ys)
    w, h = max(max(xs) - x0, 1e-9), max(max(ys) - y0, 1e-9)
    body = "\n".join('<path d="%s"/>' % d for d in paths)
    return ('<svg xmlns="http://www.w3.org/2000/svg" viewBox="%.17g %.17g %.17g %.17g">\n'
            '<g fill="none" stroke="black" stroke-width="%.6g">\n%s\n</g>\n</svg>\n'
            % (x0, y0, w, h, 1e-3 * max(w, h), body))


def export(args):
    os.makedirs(args.out_dir, exist_ok=True)
    rows = []
    for svg in args.files:
        if not changed_by_paint(args.bin, svg):
            continue
        stem = os.path.splitext(os.path.basename(svg))[0]
        js = os.path.join(args.out_dir, stem + ".features.json")
        run = subprocess.run([args.bin, "features", svg, "-o", js], capture_output=True, text=True)
        if run.returncode != 0:
            print("skip (features failed): %s" % svg, file=sys.stderr)
            continue
        with open(js) as f:
            features = json.load(f)
        out = os.path.join(args.out_dir, stem + ".svg")
        with open(out, "w") as f:
            f.write(feature_svg(features))
        rows.append((svg, out))
        print("%s -> %s" % (svg, out))
    with open(os.path.join(args.out_dir, "map.tsv"), "w") as f:
        for a, b in rows:
            f.write("%s\t%s\n" % (a, b))
    print("%d of %d drawings changed by the paint model" % (len(rows), len(args.files)))


def merge(args):
    original, ref_csv, map_tsv = args.merge
    exported_to_original = {}
    with open(map_tsv) as f:
        for line in f:
            a, b = line.rstrip("\n").split("\t")
            exported_to_original[b] = a
    replaced = {}
    with open(ref_csv) as f:
        for r in csv.DictReader(f):
            if r["tool"] == "ref" and r["file"] in exported_to_original:
                r["file"] = exported_to_original[r["file"]]
                replaced[r["file"]] = r
    with open(original) as f:
        reader = csv.DictReader(f)
        fields = reader.fieldnames
        rows = []
        for r in reader:
            if r["tool"] == "ref" and r["file"] in replaced:
                r = replaced[r["file"]]
            rows.append(r)
    with open(args.out, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields)
        w.writeheader()
        for r in rows:
            w.writerow({k: r.get(k, "") for k in fields})
    print("%d reference rows replaced by the same geometry's" % len(replaced))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("files", nargs="*")
    ap.add_argument("--bin", default="target/release/triwild")
    ap.add_argument("--out-dir")
    ap.add_argument("--merge", nargs=3, metavar=("ORIGINAL_CSV", "REF_CSV", "MAP_TSV"))
    ap.add_argument("--out")
    args = ap.parse_args()
    if args.merge:
        if not args.out:
            ap.error("--merge needs --out")
        merge(args)
    else:
        if not args.out_dir:
            ap.error("--out-dir is needed")
        export(args)


if __name__ == "__main__":
    main()
