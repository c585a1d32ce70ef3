"""Load histories as data: callables that pickle, so that a load can run wherever its
particles live (an engine's worker has neither scikit-fem nor the orchestrator's closures)."""
from __future__ import annotations

import numpy as np


class Table:
    """Piecewise-linear curve through (t (k,) s, value (k,)), zero outside, times ``scale``: a
    callable that pickles (a load may travel to an engine's worker with its particles)."""

    def __init__(self, t: np.ndarray, value: np.ndarray, scale: float = 1.0):
        self.t, self.value, self.scale = np.asarray(t, float), np.asarray(value, float), scale

    def __call__(self, s: float) -> float:
        return self.scale * float(np.interp(s, self.t, self.value, left=0.0, right=0.0))
