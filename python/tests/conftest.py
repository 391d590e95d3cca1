"""Shared fixtures: the repository, the installed `triwild` command, scratch dirs."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
SVG = REPO / "data" / "svg"

SQUARE = (
    b'<svg xmlns="http://www.w3.org/2000/svg" width="10" height="10">'
    b'<rect id="plate" x="1" y="1" width="8" height="8" fill="grey"/></svg>'
)


def cli_exe() -> str:
    """The `triwild` command installed beside this interpreter (the wheel's)."""
    exe = Path(sys.executable).parent / "triwild"
    if exe.exists():
        return str(exe)
    found = shutil.which("triwild")
    assert found, "the triwild command is not installed"
    return found


def run_cli(*args: str, **kw) -> subprocess.CompletedProcess:
    return subprocess.run(
        [cli_exe(), *map(str, args)], capture_output=True, text=True, timeout=600, **kw
    )


@pytest.fixture
def square_svg(tmp_path: Path) -> Path:
    p = tmp_path / "square.svg"
    p.write_bytes(SQUARE)
    return p


def pytest_configure(config):
    os.environ.setdefault("MPLBACKEND", "Agg")
