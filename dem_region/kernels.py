"""Compiled loops of the engine adapters."""
from __future__ import annotations

from physics.compiled import kernel


@kernel
def add_held_forces(added, F, V, rows, G, takes, half_dt, mass):
    """Added forces G (k, 3) N on engine rows (k,): all into ``added`` (what ``forces``
    reports), and the components that move (takes (k, 3) bool) into the engine's force F and,
    for their missing final half kick, velocity V += (dt / 2) G / m (mass (k,) kg)."""
    for r in range(rows.shape[0]):
        p = rows[r]
        for k in range(3):
            added[p, k] += G[r, k]
            if takes[r, k]:
                F[p, k] += G[r, k]
                V[p, k] += half_dt * G[r, k] / mass[r]
