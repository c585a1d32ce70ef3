"""Where a softened cohesive pair rings under central differences, with and without its damper.

A pair of masses joined by a softened penalty spring (K in compression, r K in opening, r = 1 - d)
is, in its relative motion, the bilinear map u+ = 2 u - u- - (omega dt)^2 s(u) u with s = 1 for
u < 0 and r for u > 0. Each branch alone is stable below omega dt = 2; the switched map grows in
resonance tongues well inside it. This scans omega dt and r over random starts (vectorised, an
implementation independent of LawBonds) and prints the smallest omega dt at which some start
grows past 100 x its size within STEPS steps, for: no damper; a damper of ratio xi on the rate
(lagged half a step, as the law's) acting at contact only (u < 0 now or at the last step: what
participants.fem.pair_damping does); and one acting always.

    .venv/bin/python benchmarks/pair_ringing.py [--xi 0.1] [--steps 20000]
"""
from __future__ import annotations

import argparse

import numpy as np


def smallest_ringing(xi: float, gate: str, steps: int, wdt=np.linspace(0.2, 1.9, 86), r=np.linspace(0.01, 0.99, 50),
                     starts: int = 16, seed: int = 1) -> float:
    """Smallest omega dt of the grid at which some (r, start) grows 100 x (nan if none)."""
    w, rr = np.meshgrid(wdt, r, indexing="ij")
    stiff = (w**2)[..., None]
    soft = (rr * w**2)[..., None]
    c = (2 * xi * w)[..., None]  # c dt / m, the damper in the map's units
    rng = np.random.default_rng(seed)
    u = rng.normal(size=w.shape + (starts,))
    v = rng.normal(size=w.shape + (starts,))  # dt times the velocity at the half step
    u_old = u - v
    size = np.maximum(abs(u), abs(v))
    peak = np.zeros_like(u)
    for _ in range(steps):
        contact = u < 0
        on = {"none": False, "contact": contact | (u_old < 0), "always": True}[gate]
        v = v - np.where(contact, stiff, soft) * u - np.where(on, c, 0.0) * v
        u_old, u = u, u + v
        np.maximum(peak, abs(u), out=peak)
        np.clip(u, -1e8, 1e8, out=u)
        np.clip(v, -1e8, 1e8, out=v)
    rings = ((peak / size).max(axis=2) > 100).any(axis=1)
    return float(wdt[rings].min()) if rings.any() else float("nan")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--xi", type=float, default=0.1)
    ap.add_argument("--steps", type=int, default=20000)
    a = ap.parse_args()
    print(f"| damper (xi = {a.xi}) | smallest omega dt that rings |")
    print("|---|---|")
    for gate, what in (("none", "none"), ("contact", "at contact (the far field's)"), ("always", "always")):
        print(f"| {what} | {smallest_ringing(a.xi if gate != 'none' else 0.0, gate, a.steps):.2f} |")
    print(f"(linear limits: 2 undamped, {2 * (np.sqrt(1 + a.xi**2) - a.xi):.2f} damped)")


if __name__ == "__main__":
    main()
