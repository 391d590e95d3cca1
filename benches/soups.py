#!/usr/bin/env python3
"""Write the stroked soups that measure the crossing-density judgement
(`src/pipeline/density.rs`, `docs/tuning.md` "Input density").

    python3 benches/soups.py OUT_DIR [--cases lines,fan,circles]

- `lines`: 2 000 line segments, ends uniform in a 100 x 100 viewBox
  (`random.Random(5)`), stroked black, width 1: about nine strokes deep, so most
  crossings of their outlines lie inside the union of the strokes.
- `fan`: 1 000 lines from (0, 0.1 k) to (100, 100 - 0.1 k), k = 0..999, stroked
  black, width 1, in a 100 x 100 viewBox: all through (50, 50), 0.1 apart at the
  sides.
- `circles`: 5 000 circles, centres uniform in a 1000 x 1000 viewBox, radii
  uniform in [2, 12], stroke widths uniform in [0.2, 1.5] (`random.Random(5)`),
  unfilled.

Python 3 standard library only; the same files on every run.
"""

import argparse
import os
import random

HEAD = '<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {w} {w}">\n'
LINE = '<line x1="{:.4f}" y1="{:.4f}" x2="{:.4f}" y2="{:.4f}" stroke="#000" stroke-width="1"/>\n'


def lines(n=2000, seed=5):
    rnd = random.Random(seed)
    out = [HEAD.format(w=100)]
    for _ in range(n):
        x0, y0, x1, y1 = (rnd.uniform(0, 100) for _ in range(4))
        out.append(LINE.format(x0, y0, x1, y1))
    out.append("</svg>\n")
    return "".join(out)


def fan(n=1000):
    out = [HEAD.format(w=100)]
    for k in range(n):
        out.append(LINE.format(0, 0.1 * k, 100, 100 - 0.1 * k))
    out.append("</svg>\n")
    return "".join(out)


def circles(n=5000, seed=5):
    rnd = random.Random(seed)
    out = [HEAD.format(w=1000)]
    for _ in range(n):
        cx, cy = rnd.uniform(0, 1000), rnd.uniform(0, 1000)
        r = rnd.uniform(2, 12)
        w = rnd.uniform(0.2, 1.5)
        out.append(
            f'<circle cx="{cx:.4f}" cy="{cy:.4f}" r="{r:.4f}" fill="none" '
            f'stroke="#000" stroke-width="{w:.4f}"/>\n'
        )
    out.append("</svg>\n")
    return "".join(out)


CASES = {"lines": lines, "fan": fan, "circles": circles}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out_dir")
    ap.add_argument("--cases", default=",".join(CASES))
    args = ap.parse_args()
    os.makedirs(args.out_dir, exist_ok=True)
    for name in args.cases.split(","):
        path = os.path.join(args.out_dir, f"{name}.svg")
        with open(path, "w") as f:
            f.write(CASES[name]())
        print(path)


if __name__ == "__main__":
    main()
