"""Errors are exceptions with the command line's one-line messages; none
crashes the interpreter. The table is tests/cli_errors.rs's."""

from __future__ import annotations

import subprocess
import sys

import pytest

import triwild
from conftest import SQUARE, run_cli

PNG_MAGIC = b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR"

# (name, input bytes or a kind of path, the exception, a word of the cause)
INPUTS = [
    ("missing", "missing", triwild.BadInput, "no such file"),
    ("directory", "directory", triwild.BadInput, "directory"),
    ("empty", b"", triwild.BadInput, "empty"),
    ("not-xml", b"hello, this is plain text\n", triwild.BadInput, "svg"),
    ("broken-xml", b'<svg xmlns="http://www.w3.org/2000/svg"><path d="M0 0 L1 1"</svg>', triwild.BadInput, "svg"),
    ("html", b"<!DOCTYPE html><html><head><title>x</title></head><body><p>hi</p></body></html>", triwild.BadInput, "svg"),
    ("png", PNG_MAGIC, triwild.BadInput, "svg"),
    ("no-geometry", b'<svg xmlns="http://www.w3.org/2000/svg" width="10" height="10"><title>nothing</title></svg>', triwild.BadInput, "geometry"),
    ("nan", b'<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 10 10"><path d="M 0 0 L NaN 5 L 5 5 Z"/></svg>', triwild.BadInput, "non-finite"),
    ("infinity", b'<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 10 10"><polygon points="0,0 Infinity,5 5,5"/></svg>', triwild.BadInput, "non-finite"),
    ("huge", b'<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 10 10"><path d="M 0 0 L 1e300 5 L 5 5 Z"/></svg>', triwild.BadInput, "coordinate"),
    ("infinite-transform", b'<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 10 10"><path transform="scale(1e200)" d="M 0 0 L 1e200 5 L 5 5 Z"/></svg>', triwild.BadInput, ""),
]
CODES = {triwild.BadInput: 2, triwild.MeshingError: 3, triwild.IoError: 4}


def _input(tmp_path, what):
    p = tmp_path / "in.svg"
    if what == "missing":
        return p
    if what == "directory":
        p.mkdir()
        return p
    p.write_bytes(what)
    return p


@pytest.mark.parametrize("name,what,exc,cause", INPUTS, ids=[c[0] for c in INPUTS])
def test_bad_input_raises_the_cli_error(tmp_path, name, what, exc, cause):
    path = _input(tmp_path, what)
    with pytest.raises(exc) as info:
        triwild.mesh(path)
    msg = str(info.value)
    assert isinstance(info.value, triwild.Error)
    assert "\n" not in msg and cause in msg.lower(), msg
    # the command line prints the same line after `error: ` and exits with the kind's code
    r = run_cli(path, "-o", tmp_path / "out.msh")
    assert r.returncode == CODES[exc], r.stderr
    assert r.stderr.strip() == f"error: {msg}"
    # and the document itself, as bytes or text, raises the same kind
    if isinstance(what, bytes):
        with pytest.raises(exc) as from_bytes:
            triwild.mesh(what)
        assert str(from_bytes.value) == msg.split(": ", 1)[1]


@pytest.mark.parametrize(
    "output,cause",
    [("no/such/dir/out.msh", ""), ("a-file/out.msh", ""), ("a-dir", "directory")],
)
def test_unwritable_output_raises_ioerror(tmp_path, output, cause):
    (tmp_path / "a-file").write_text("x")
    (tmp_path / "a-dir").mkdir()
    m = triwild.mesh(SQUARE, order=1)
    target = tmp_path / output
    with pytest.raises(triwild.IoError) as info:
        m.write(target)
    assert str(info.value).startswith(f"{target}: ") and cause in str(info.value)
    assert not (tmp_path / "no").exists()
    (tmp_path / "in.svg").write_bytes(SQUARE)
    r = run_cli(tmp_path / "in.svg", "-o", target)
    assert r.returncode == 4 and r.stderr.strip() == f"error: {info.value}"


def test_bad_values_raise_badinput_and_unknown_keywords_typeerror():
    with pytest.raises(triwild.BadInput):
        triwild.mesh(SQUARE, edge_length=-1)
    with pytest.raises(triwild.BadInput, match="order"):
        triwild.mesh(SQUARE, order=5)
    with pytest.raises(triwild.BadInput, match="regions"):
        triwild.mesh(SQUARE, regions="everything")
    with pytest.raises(triwild.BadInput):
        triwild.mesh(SQUARE, linear=True, stop_after="bsp")
    with pytest.raises(TypeError):
        triwild.mesh(SQUARE, no_such_flag=1)
    with pytest.raises(TypeError):
        triwild.mesh(12345)
    with pytest.raises(ValueError):
        triwild.mesh(SQUARE, order=1).write("/tmp/x.msh", version="3.0")


def test_check_of_a_bad_file_raises(tmp_path):
    bad = tmp_path / "bad.msh"
    bad.write_text("$MeshFormat\nnonsense\n")
    with pytest.raises(triwild.Error):
        triwild.check(bad)
    with pytest.raises(triwild.Error):
        triwild.check(tmp_path / "missing.msh")


def test_no_bad_input_crashes_the_interpreter(tmp_path):
    # every case in a child interpreter: it must exit normally, having caught
    # the exception (an abort or a signal would show as another return code)
    code = (
        "import sys, triwild\n"
        "for data in sys.argv[1:]:\n"
        "    try:\n"
        "        triwild.mesh(bytes.fromhex(data))\n"
        "    except triwild.Error:\n"
        "        pass\n"
        "    else:\n"
        "        sys.exit(5)\n"
        "print('ok')\n"
    )
    datas = [w.hex() for _, w, _, _ in INPUTS if isinstance(w, bytes)]
    r = subprocess.run([sys.executable, "-c", code, *datas], capture_output=True, text=True)
    assert r.returncode == 0 and r.stdout.strip() == "ok", r.stderr
