"""The `triwild` command the wheel installs, and `python -m triwild`."""

from __future__ import annotations

import json
import subprocess
import sys

from conftest import SQUARE, SVG, run_cli


def test_help_and_version():
    r = run_cli("--help")
    assert r.returncode == 0 and "Exit codes" in r.stdout, r.stderr
    r = subprocess.run([sys.executable, "-m", "triwild", "--version"], capture_output=True, text=True)
    assert r.returncode == 0 and r.stdout.startswith("triwild "), r.stderr


def test_usage_error_exits_2():
    r = run_cli("x.svg", "--no-such-flag")
    assert r.returncode == 2 and "no-such-flag" in r.stderr


def test_mesh_and_check(tmp_path):
    out = tmp_path / "ello.msh"
    r = run_cli(SVG / "ello.svg", "-o", out, "--order", "2")
    assert r.returncode == 0, r.stderr
    r = run_cli("check", out)
    assert r.returncode == 0, r.stdout + r.stderr


def test_batch_runs_its_children_through_this_python(tmp_path):
    src = tmp_path / "in"
    src.mkdir()
    (src / "a.svg").write_bytes(SQUARE)
    (src / "b.svg").write_bytes((SVG / "ello.svg").read_bytes())
    (src / "bad.svg").write_bytes(b"not svg")
    out = tmp_path / "out"
    r = run_cli("batch", src, "-o", out, "--jobs", "2", "--order", "2", "--quiet")
    assert r.returncode == 1, r.stdout + r.stderr  # one file failed
    rows = [json.loads(line) for line in (out / "report.jsonl").read_text().splitlines()]
    status = {
        row["file"].split("/")[-1]: (row["status"], row.get("cause")) for row in rows if "file" in row
    }
    assert status == {
        "a.svg": ("ok", None),
        "b.svg": ("ok", None),
        "bad.svg": ("failed", "bad-input"),
    }, rows
    assert sorted(p.name for p in out.rglob("*.msh")) == ["a.msh", "b.msh"]
