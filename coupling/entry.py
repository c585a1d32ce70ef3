"""The ``femdem`` command's entry point. The command line's modules take a few seconds to import
(numba, scipy, the scenes); a Ctrl-C in them ends the command as one during a run does, in one
line and exit 130, once they have loaded. Raised inside them it was not safe: tracebacks,
scipy's decorator module printing a wrapper's source before re-raising (a bare except), and an
import that swallowed it and ran the whole command (exit 0; both seen in CI). So SIGINT is held
blocked while they load and delivered, if it came, when they are done."""
from __future__ import annotations

import signal
import sys
import threading


def main(argv: list[str] | None = None) -> int:
    # (only where Python's own handler would raise it, and in the one thread a command starts
    # with: threads the imports start inherit the mask and leave SIGINT to this one)
    hold = (hasattr(signal, "pthread_sigmask") and threading.current_thread() is threading.main_thread()
            and signal.getsignal(signal.SIGINT) is signal.default_int_handler)
    try:
        if hold:
            signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
        try:
            from .cli import main as command
        finally:
            if hold:  # a Ctrl-C held meanwhile is raised here
                signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    except KeyboardInterrupt:
        print("femdem: interrupted", file=sys.stderr)
        return 130
    return command(argv)
