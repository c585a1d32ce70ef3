"""Seconds this process has spent compiling kernels.

A kernel is compiled the first time a process calls it with a signature its disk cache does not
hold: on a new machine, after its sources changed (physics/kernel_cache.py), or for a build no
earlier run used (the ply bonds' parallel pass, which only a large family takes). That cost
belongs to the installation, not to the model: the seed beam's all-DEM reference took 62 s on a
fresh machine where the same run took 43 s once its kernels were cached, and a bench's ratio
against it read 7.4 x instead of 4.9 x. summary.json reports it (``timing_s.compile``, part of
``total``) and ``femdem bench`` leaves it out of the wall times it compares.

numba announces each compilation as a "numba:compile" event (cache loads are not one); a kernel's
callees compile inside its event, so only the outermost events are counted.
"""
from __future__ import annotations

import time

from numba.core import event


class _Clock(event.Listener):
    def __init__(self):
        self.seconds, self._depth, self._t0 = 0.0, 0, 0.0
        self.announce = None  # called before the next compilation, once

    def on_start(self, ev) -> None:
        if self._depth == 0:
            if self.announce is not None:
                say, self.announce = self.announce, None
                say()
            self._t0 = time.perf_counter()
        self._depth += 1

    def on_end(self, ev) -> None:
        self._depth -= 1
        if self._depth == 0:
            self.seconds += time.perf_counter() - self._t0


_CLOCK = _Clock()
event.register("numba:compile", _CLOCK)


def compile_seconds() -> float:
    """s: this process's kernel compilations so far (outermost, wall time)."""
    return _CLOCK.seconds


def announce_once(say) -> None:
    """``say()`` before this process's next compilation (once; None: nothing). An interactive
    run says why its first minute on a new machine shows nothing else (coupling/run.py)."""
    _CLOCK.announce = say
