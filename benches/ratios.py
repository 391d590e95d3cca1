#!/usr/bin/env python3
"""Several runs of triwild against one reference run, side by side.

    benches/ratios.py REF.csv NAME=RUN.csv [NAME=RUN.csv ...] [--base NAME]

Each CSV is what `../shared/bench/compare.py` writes; REF.csv must hold `ref` rows, each RUN.csv
`ours` rows (a run of one triwild build or option set). Per run, over the drawings both it and
the reference meshed valid: the median per-drawing ratio of triangles ours / reference (what
`judge.py` bounds), the ratio of the totals, the median per-drawing ratio of the minimum angles,
and with `--base` the same triangle and time ratios against that run instead of the reference.
Used for the triangle ratio against the reference, one choice at a time (benches/README.md).
"""
import argparse
import csv
import statistics

COLUMNS = ("tool,file,status,exit,wall_s,cpu_s,t_core,peak_rss_mb,n_tri,n_curved,min_angle,"
           "n_inverted,min_detj_ratio,gmsh_min_detj_ratio,nonconforming_edges,area,valid,"
           "check_exit,reasons,note").split(",")


def load(path, tool):
    """Valid rows of one tool, by file (the header may be missing: rows appended by --resume)."""
    rows = {}
    for row in csv.reader(open(path)):
        if not row or row[0] != tool:
            continue
        r = dict(zip(COLUMNS, row))
        if r["status"] == "ok" and r["valid"] in ("True", "true", "1"):
            rows[r["file"]] = r
    return rows


def ratio_line(a, b, files):
    """Median and total ratios of b over a on `files`."""
    tri = [int(b[f]["n_tri"]) / int(a[f]["n_tri"]) for f in files]
    total = sum(int(b[f]["n_tri"]) for f in files) / sum(int(a[f]["n_tri"]) for f in files)
    ang = [float(b[f]["min_angle"]) / float(a[f]["min_angle"])
           for f in files if float(a[f]["min_angle"]) > 0]
    time = [float(b[f]["wall_s"]) / float(a[f]["wall_s"]) for f in files]
    return (statistics.median(tri), total, statistics.median(ang), statistics.median(time),
            sum(x <= 0.8 for x in tri) / len(tri))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("ref")
    ap.add_argument("runs", nargs="+", help="NAME=RUN.csv")
    ap.add_argument("--base", help="a NAME of the runs: ratios against it as well")
    a = ap.parse_args()
    ref = load(a.ref, "ref")
    runs = {}
    for spec in a.runs:
        name, _, path = spec.partition("=")
        runs[name] = load(path, "ours")
    common = sorted(set(ref).intersection(*[set(r) for r in runs.values()]))
    print(f"{len(common)} drawings meshed valid by the reference and every run")
    print(f"{'run':<16} {'tri/ref med':>11} {'total':>7} {'<=0.8':>6} {'angle/ref':>9} {'time/ref':>8}"
          + (f" {'tri/base med':>12} {'total':>7} {'time/base':>9}" if a.base else ""))
    for name, run in runs.items():
        t, tot, ang, tim, share = ratio_line(ref, run, common)
        line = f"{name:<16} {t:>11.3f} {tot:>7.3f} {share:>6.0%} {ang:>9.2f} {tim:>8.3f}"
        if a.base:
            bt, btot, _, btim, _ = ratio_line(runs[a.base], run, common)
            line += f" {bt:>12.3f} {btot:>7.3f} {btim:>9.3f}"
        print(line)


main()
