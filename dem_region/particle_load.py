"""A prescribed load history on engine particles, applied by the coupling layer (any engine).

A measured drop-weight load (a force against time, not an impactor whose motion we would
have to model) acts on a patch of surface particles: each step the model adds
``curve(t_k) * share`` to them, with t_k the time of the positions the engine just computed
forces for. Its work is summed by the trapezoidal rule on the particles' displacements and
enters the energy ledger as external work.
"""
from __future__ import annotations

from typing import Callable

import numpy as np


class ParticleLoad:
    """ids: (k,) particle ids; share: (k, 3) N per unit of curve(t) on each particle;
    curve: t (s) -> load amplitude (the total force is curve(t) * share.sum(axis=0))."""

    def __init__(self, ids: np.ndarray, share: np.ndarray, curve: Callable[[float], float]):
        self.ids = np.asarray(ids, int)
        self.share = np.asarray(share, float).reshape(len(self.ids), 3)
        self.curve = curve
        self.time = 0.0
        self.work = 0.0
        self._x_prev: np.ndarray | None = None
        self._f_prev = np.zeros_like(self.share)

    def critical_dt(self, particle_mass: np.ndarray) -> float:
        return np.inf  # a force history adds no stiffness

    def force(self) -> np.ndarray:
        """(3,) N, the total load now."""
        return self.curve(self.time) * self.share.sum(axis=0)

    def apply(self, engine, dt: float) -> None:
        self.time += dt
        x = engine.positions_of(self.ids)
        f = self.curve(self.time) * self.share
        if self._x_prev is not None:
            self.work += 0.5 * float(np.sum((self._f_prev + f) * (x - self._x_prev)))
        self._x_prev, self._f_prev = x, f
        if np.any(f):
            engine.add_forces(self.ids, f)

    def energies(self) -> dict[str, float]:
        return {"kinetic": 0.0, "internal": 0.0, "dissipated": 0.0, "external_work": self.work}

    def momentum(self) -> np.ndarray:
        return np.zeros(3)  # the load carries no mass

    def checkpoint_state(self) -> dict:
        d = {"time": self.time, "work": self.work, "f_prev": self._f_prev}
        if self._x_prev is not None:
            d["x_prev"] = self._x_prev
        return d

    def restore_state(self, d: dict) -> None:
        self.time, self.work = float(d["time"]), float(d["work"])
        self._f_prev = np.array(d["f_prev"])
        self._x_prev = np.array(d["x_prev"]) if "x_prev" in d else None
