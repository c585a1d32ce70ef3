"""The back-end contract: one small class shaped like a coupling participant (preCICE style).

Order of calls: ``build(scene)`` once; ``set_dt``; ``start(between)`` once (forces at x_0,
then ``between()``); then ``advance(between, steps)``, which for each of its steps (1) moves every particle with
the forces of the current positions (leapfrog: v_{k+1/2} = v_{k-1/2} + dt F_k / m,
x_{k+1} = x_k + dt v_{k+1/2}; prescribed particles keep the velocity last written),
(2) computes the forces at x_{k+1}, (3) calls ``between()``, where the orchestrator reads
interface forces and writes the interface velocities of the next move.
Array data moves in bulk: ids (k,) int, vectors (k, 3) SI.
"""
from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Callable, Protocol

import numpy as np

from ..scene import DemScene


def scratch_dir(engine: str) -> Path:
    """A new directory for an engine's data file and log: under $FEMDEM_SCRATCH_DIR when the
    orchestrator set it (inside the run directory, so a killed run leaves nothing in /tmp and
    the log stays with the run), else in the system's temporary directory."""
    root = os.environ.get("FEMDEM_SCRATCH_DIR")
    if root:
        os.makedirs(root, exist_ok=True)
    return Path(tempfile.mkdtemp(prefix=f"{engine}-", dir=root or None))


class EngineUnavailable(ValueError):
    """The engine is unknown, not installed or not implemented (bad input, exit code 2)."""


class DemBackend(Protocol):
    name: str
    version: str
    native_laws: tuple[str, ...]

    def build(self, scene: DemScene) -> None: ...

    def critical_dt(self) -> float: ...

    def set_dt(self, dt: float) -> None: ...

    def start(self, between: Callable[[], None] | None = None) -> None: ...

    def advance(self, between: Callable[[], None] | None = None, steps: int = 1) -> None:
        """``steps`` engine steps, ``between()`` after each step's forces. An engine in a worker
        crosses the process boundary once per call, not once per step; if ``between`` raises,
        the steps after it are not taken and the exception propagates."""

    def prescribe(self, ids: np.ndarray) -> None:
        """Slave particles ``ids`` (their motion comes from set_velocities only)."""

    def set_velocities(self, ids: np.ndarray, v: np.ndarray) -> None: ...

    def forces(self, ids: np.ndarray) -> np.ndarray:
        """(k, 3) N: force the rest of the scene exerts on particles ``ids`` at this step."""

    def forces_into(self, ids: np.ndarray, out: np.ndarray) -> None:
        """``forces(ids)`` written into out (k, 3) N: the interface's each step, without a
        temporary where the engine's arrays allow it."""

    def add_forces(self, ids: np.ndarray, F: np.ndarray) -> None:
        """Add forces F (k, 3) N to particles ``ids`` for the next move (penalty tie)."""

    def positions_of(self, ids: np.ndarray) -> np.ndarray:
        """(k, 3) m, current positions of particles ``ids``."""

    def positions(self) -> np.ndarray: ...

    def velocities(self) -> np.ndarray: ...

    def energies(self) -> dict[str, float]:
        """{kinetic, elastic, dissipated} J, as far as the engine reports them."""

    def bond_state(self) -> dict:
        """{intact, broken, broken_list}: counts and rows (i, j, t, x, y, z) of broken bonds."""

    supports_checkpoint: bool  # False where the engine's state cannot be saved whole (contact history)

    def checkpoint(self, path) -> None:
        """Save the engine state to ``path`` (the engine's own restart format), atomically."""

    def restore(self, path) -> None:
        """Continue from a checkpoint: the next ``advance`` is the one that followed it."""

    def finalize(self) -> None: ...
