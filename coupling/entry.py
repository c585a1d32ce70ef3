"""The ``femdem`` command's entry point. The command line's modules take a few seconds to import
(numba, scipy, the scenes); a Ctrl-C in them ends the command as one during a run does, in one
line and exit 130, where it printed the import's traceback. What the imports write to stderr
meanwhile is held and passed on once they finish or fail: interrupted inside scipy's generated
wrappers, its decorator module prints their source before it re-raises (a bare except)."""
from __future__ import annotations

import io
import sys


def main(argv: list[str] | None = None) -> int:
    stderr, held = sys.stderr, io.StringIO()
    interrupted = False
    try:
        if stderr is not None:  # (closed, 2>&-: nothing to hold)
            sys.stderr = held
        from .cli import main as command
    except KeyboardInterrupt:
        interrupted = True
    finally:
        sys.stderr = stderr
        if not interrupted and stderr is not None:  # (a failed import's explanation comes before its traceback)
            stderr.write(held.getvalue())
    if interrupted:
        if stderr is not None:
            print("femdem: interrupted", file=stderr)
        return 130
    return command(argv)
