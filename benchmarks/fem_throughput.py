"""Element updates per second of the explicit FEM far field (linear and TL paths).

Usage: .venv/bin/python benchmarks/fem_throughput.py [--elements 10000 100000] [--repeat 5]
Prints a markdown table; each figure is the median over ``repeat`` timings of 50 steps.
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from fem_region import materials, mesh
from fem_region.elements import ELEMENTS
from fem_region.explicit import ExplicitDynamics
from fem_region.region import FemRegion


def measure(n_el: int, element: str, integration: str, formulation: str, repeat: int, steps: int = 50) -> float:
    ny = max(1, int(np.sqrt(n_el / 10)))
    nx = n_el // ny
    m = mesh.rectangle(np.linspace(0, 10, nx + 1), np.linspace(0, 1, ny + 1), element)
    D = materials.plane_strain(materials.isotropic(70e9, 0.3))
    dyn = ExplicitDynamics(FemRegion(m, ELEMENTS[element], D, 2700.0, 1.0, integration, formulation))
    dyn.set_initial_velocity(1e-3 * np.random.default_rng(0).standard_normal((dyn.region.n_nodes, 2)))
    dt = 0.9 * dyn.critical_dt()
    dyn.start()
    dyn.step(dt)  # compile / warm caches
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(steps):
            dyn.step(dt)
        times.append((time.perf_counter() - t0) / steps)
    return dyn.region.n_elements / float(np.median(times)), float(np.median(times))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--elements", type=int, nargs="+", default=[10_000, 100_000])
    ap.add_argument("--repeat", type=int, default=5)
    a = ap.parse_args()
    print("| elements | element | integration | path | step [ms] | element updates / s |")
    print("|---|---|---|---|---|---|")
    for n in a.elements:
        for el, integ, form in [("quad4", "full", "linear"), ("quad4", "selective", "linear"),
                                ("quad4", "reduced", "linear"), ("quad4", "full", "total_lagrangian"),
                                ("quad4", "selective", "total_lagrangian"), ("tri3", "full", "total_lagrangian")]:
            rate, step = measure(n, el, integ, form, a.repeat)
            print(f"| {n:,} | {el} | {integ} | {form} | {step * 1e3:.2f} | {rate:.3g} |", flush=True)


if __name__ == "__main__":
    main()
