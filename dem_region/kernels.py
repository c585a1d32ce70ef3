"""Compiled loops of the engine adapters."""
from __future__ import annotations

import numpy as np

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
def take_rows(out, X, ids):
    """out (k, 3) <- X[ids] (X (N, 3), ids (k,)): numpy's take into a buffer, without its
    call's cost (~2 us: the laws' read of their particles at every step)."""
    for r in range(ids.shape[0]):
        p = ids[r]
        for k in range(3):
            out[r, k] = X[p, k]


@kernel
def put_components(V, rows, comps, src, v):
    """V[rows[e], comps[e]] = v[src[e], comps[e]] for each entry e: a velocity write of the
    components a plan selected (rows (m,) engine rows, src (m,) rows of v (k, 3))."""
    for e in range(rows.shape[0]):
        V[rows[e], comps[e]] = v[src[e], comps[e]]


@kernel
def spring_energy(X, bonds, K, r0):
    """J, sum over bonds (b, 2) of K (|x_j - x_i| - r0)^2 (K (b,) N/m: the engine's harmonic
    bond coefficient, half the spring's stiffness; r0 (b,) m) at positions X (n, 3) m, without
    temporaries (at every sample; an all-DEM beam's 9,534 placeholder springs took 0.7 ms in numpy)."""
    e = 0.0
    for b in range(bonds.shape[0]):
        i, j = bonds[b, 0], bonds[b, 1]
        r = np.sqrt((X[j, 0] - X[i, 0]) ** 2 + (X[j, 1] - X[i, 1]) ** 2 + (X[j, 2] - X[i, 2]) ** 2)
        e += K[b] * (r - r0[b]) ** 2
    return e


@kernel
def free_kinetic_energy(mass, radius, V, W, held, driven):
    """J, translation and rotation of the particles the engine moves: mass (n,) kg, radius (n,) m,
    velocities V and spins W (n, 3); held (n,) bool (prescribed, fixed: none of theirs counts)
    and driven (n, 3) bool (a symmetry plane's held components: no translation there)."""
    e = 0.0
    for p in range(mass.shape[0]):
        if held[p]:
            continue
        t = 0.0
        for k in range(3):
            if not driven[p, k]:
                t += V[p, k] * V[p, k]
        w = W[p, 0] * W[p, 0] + W[p, 1] * W[p, 1] + W[p, 2] * W[p, 2]
        e += mass[p] * t + 0.4 * mass[p] * radius[p] ** 2 * w
    return 0.5 * e
