#!/usr/bin/env python3
"""`--threads 2` against `--threads 1`, for one or more builds.

For each drawing, runs every build at one and two threads, REPS rounds
interleaved (build A t1, A t2, build B t1, B t2, ... then again), keeps each
configuration's best wall time, and checks that one and two threads wrote the
same bytes. Interleaving matters on a shared machine: its speed drifts by 10 %
and more within minutes, so builds measured one after the other are not
comparable. Python 3 standard library only.

    cargo build --release --locked
    python3 benches/threads.py [--reps 5] [--svg-dir ../shared/data/svg-dev]
        [--files a.svg,b.svg | --largest 10] BIN [BIN ...]

The default drawings are three of the slowest of the dev set.
Prints a line per drawing: each build's best t1, t2 and t1/t2, then each
build's median t1/t2 over the drawings and, per stage (`--stats` `times` of
the best runs, summed over the drawings), t1, t2 and t1/t2, so the part that
stays sequential is visible.
"""

import argparse
import filecmp
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

SLOWEST = [
    "gcompris/chronos__resource__images__renault_voiturette.svg",
    "gcompris/instruments__resource__organ.svg",
    "noto-emoji/emoji_u1f98e.svg",
]


def run(binary, svg, out, threads, refused_ok=False):
    """Wall seconds of one run and its stages' seconds; exits on a failed run
    (with `refused_ok`, returns None where the input is refused: exit 2)."""
    start = time.perf_counter()
    done = subprocess.run(
        [binary, svg, "-o", out, "--threads", str(threads), "--stats", "-q"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    wall = time.perf_counter() - start
    if refused_ok and done.returncode == 2:
        return None
    if done.returncode != 0:
        sys.exit(f"{binary} {svg} --threads {threads}: exit {done.returncode}: {done.stderr.strip()}")
    try:
        stages = json.loads(done.stdout).get("times", {})
    except json.JSONDecodeError:
        stages = {}
    return wall, stages


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("bins", nargs="+", help="triwild binaries to compare")
    ap.add_argument("--reps", type=int, default=5, help="interleaved rounds (best of)")
    ap.add_argument(
        "--svg-dir",
        default=os.path.join(here, "..", "..", "shared", "data", "svg-dev"),
        help="folder the drawings are relative to",
    )
    ap.add_argument("--files", help="comma-separated drawings (default: the three slowest)")
    ap.add_argument(
        "--largest",
        type=int,
        metavar="N",
        help="instead of --files: the N largest files of --svg-dir that mesh (as "
        "benches/README.md's \"ten largest dev drawings\"; a file the first build refuses, exit 2, is skipped "
        "and the next largest taken)",
    )
    args = ap.parse_args()
    files = args.files.split(",") if args.files else SLOWEST
    wanted = None
    if args.largest:
        sized = []
        for root, _, names in os.walk(args.svg_dir):
            for name in names:
                if name.endswith(".svg"):
                    path = os.path.join(root, name)
                    sized.append((-os.path.getsize(path), os.path.relpath(path, args.svg_dir)))
        files = [rel for _, rel in sorted(sized)]
        wanted = args.largest
    differ = False
    ratios = {b: [] for b in args.bins}
    # (build, threads) -> stage -> seconds of the best runs, summed over drawings
    stage_sum = {(b, t): {} for b in args.bins for t in (1, 2)}
    measured = 0
    with tempfile.TemporaryDirectory() as tmp:
        for rel in files:
            if wanted is not None and measured == wanted:
                break
            svg = os.path.join(args.svg_dir, rel)
            if wanted is not None and run(args.bins[0], svg, os.path.join(tmp, "probe.msh"), 1, True) is None:
                print(f"{os.path.basename(rel)[:30]:30} | skipped: refused (exit 2)", flush=True)
                continue
            measured += 1
            best = {}
            best_stages = {}
            for _ in range(args.reps):
                for b in args.bins:
                    outs = {}
                    for t in (1, 2):
                        outs[t] = os.path.join(tmp, f"t{t}.msh")
                        wall, stages = run(b, svg, outs[t], t)
                        if wall < best.get((b, t), float("inf")):
                            best[(b, t)] = wall
                            best_stages[(b, t)] = stages
                    if not filecmp.cmp(outs[1], outs[2], shallow=False):
                        print(f"OUTPUT DIFFERS: {b} {rel}", file=sys.stderr)
                        differ = True
            cells = [
                f"{os.path.basename(b)} t1 {best[(b, 1)]:.2f} t2 {best[(b, 2)]:.2f} "
                f"x{best[(b, 1)] / best[(b, 2)]:.3f}"
                for b in args.bins
            ]
            print(f"{os.path.basename(rel)[:30]:30} | " + " | ".join(cells), flush=True)
            for b in args.bins:
                ratios[b].append(best[(b, 1)] / best[(b, 2)])
                for t in (1, 2):
                    for k, v in best_stages[(b, t)].items():
                        stage_sum[(b, t)][k] = stage_sum[(b, t)].get(k, 0.0) + v
    for b in args.bins:
        median = statistics.median(ratios[b])
        print(f"{os.path.basename(b)}: median t1/t2 {median:.3f} over {len(ratios[b])} drawings")
        one, two = stage_sum[(b, 1)], stage_sum[(b, 2)]
        for k in sorted(one, key=lambda k: -one[k]):
            if k == "total" or one[k] < 0.05 or two.get(k, 0.0) <= 0.0:
                continue
            print(f"  {k:10} t1 {one[k]:7.2f} s  t2 {two[k]:7.2f} s  x{one[k] / two[k]:.2f}")
    sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()
