"""The ``femdem`` command's entry point. The command line's modules take a few seconds to import
(numba, scipy, the scenes); a Ctrl-C in them ends the command as one during a run does, in one
line and exit 130, where it printed the import's traceback."""
from __future__ import annotations

import sys


def main(argv: list[str] | None = None) -> int:
    try:
        from .cli import main as command
    except KeyboardInterrupt:
        print("femdem: interrupted", file=sys.stderr)
        return 130
    return command(argv)
