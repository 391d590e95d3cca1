"""The ``triwild`` command line, run in this process: ``python -m triwild``
and the ``triwild`` command the package installs."""

from __future__ import annotations

import signal
import sys


def main() -> None:
    """Run the command line on ``sys.argv``; exit with its code."""
    from . import _triwild

    # Ctrl-C ends the command as it ends the native binary (Python's handler
    # would only run once the Rust call returned).
    if hasattr(signal, "SIGINT"):
        signal.signal(signal.SIGINT, signal.SIG_DFL)
    argv = ["triwild", *sys.argv[1:]]
    # `triwild batch` runs one child per file: this interpreter, this module.
    child = [sys.executable, "-m", "triwild"]
    sys.stdout.flush()
    sys.exit(_triwild.cli(argv, child))


if __name__ == "__main__":
    main()
