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


@kernel
def gather_forces(out, store, added, ids):
    """out (k, 3) N <- store[ids] + added[ids]: the engine's force before any setforce and the
    forces added this step, of particles ids (k,), without a temporary (each step's interface)."""
    for r in range(ids.shape[0]):
        p = ids[r]
        for k in range(3):
            out[r, k] = store[p, k] + added[p, k]


@kernel
def put_components(V, rows, comps, src, v):
    """V[rows[e], comps[e]] = v[src[e], comps[e]] for each entry e: a velocity write of the
    components a plan selected (rows (m,) engine rows, src (m,) rows of v (k, 3))."""
    for e in range(rows.shape[0]):
        V[rows[e], comps[e]] = v[src[e], comps[e]]
