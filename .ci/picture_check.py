#!/usr/bin/env python3
"""What a viewer sees (issue 16): the mesh's colour regions against a real
renderer's picture, pixel by pixel, with ../shared/bench/picture_agree.py
(rsvg-convert renders the drawing; triwild meshes it with `--regions colour`).

Usage: picture_check.py PYTHON PICTURE_AGREE BIN OUT_DIR SVG_OR_DIR...
(PYTHON runs PICTURE_AGREE: it needs numpy, pillow and rsvg-convert on PATH.)

Every drawing given (a directory: its *.svg) is meshed by BIN and compared at
--size 1024; the check fails when a drawing does not mesh or its agreement
(agreeing / compared pixels) is below 0.999, the bar issue 16 sets for its
picture cases. Prints one line per drawing and ends with
"picture: N passed, M failed". Exit status 0 iff nothing failed.
"""

import csv
import subprocess
import sys
from pathlib import Path

MIN_AGREE = 0.999


def main() -> int:
    if len(sys.argv) < 6:
        print(__doc__, file=sys.stderr)
        return 2
    python, tool, binary, out_dir = sys.argv[1], sys.argv[2], sys.argv[3], Path(sys.argv[4])
    svgs: list[Path] = []
    for arg in sys.argv[5:]:
        p = Path(arg)
        svgs.extend(sorted(p.glob("*.svg")) if p.is_dir() else [p])
    if not svgs:
        print("picture: no drawings given", file=sys.stderr)
        return 1
    out_dir.mkdir(parents=True, exist_ok=True)
    listing = out_dir / "list.txt"
    listing.write_text("".join(f"{s.resolve()}\n" for s in svgs))
    table = out_dir / "agreement.csv"
    run = subprocess.run(
        [python, tool, "--batch", str(listing), "--bin", binary, "--out", str(table),
         "--size", "1024", "--mesh-dir", str(out_dir / "meshes")],
        capture_output=True, text=True,
    )
    if run.returncode != 0 or not table.exists():
        print(run.stdout[-2000:], run.stderr[-2000:], sep="\n", file=sys.stderr)
        print("picture: picture_agree.py failed", file=sys.stderr)
        return 1
    rows = list(csv.DictReader(table.open()))
    failed = 0
    for row in rows:
        name = Path(row["file"]).name
        agree = float(row["agree"]) if row.get("agree") else None
        if row["status"] != "ok" or agree is None or agree < MIN_AGREE:
            failed += 1
            print(f"FAILED {name}: status {row['status']}, agreement {row.get('agree')}, "
                  f"worst colours {row.get('top', '')[:200]}")
        else:
            print(f"ok     {name}: agreement {agree}, reproduced {row.get('reproduced')}")
    missing = len(svgs) - len(rows)
    failed += missing
    if missing:
        print(f"FAILED {missing} drawing(s) have no row in {table}")
    print(f"picture: {len(svgs) - failed} passed, {failed} failed")
    return 0 if failed == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
