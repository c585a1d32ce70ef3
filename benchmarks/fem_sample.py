"""What a history sample and a model's build cost the FEM far field, side by side in one run.

At every sample the inverted-element guard reads each element's smallest det F: its own
compiled pass (``FemRegion.inverted_elements``) against the St Venant-Kirchhoff energy pass
that carried it until session 34 (``_total_lagrangian_pass``, energy and det F together). At
every build (and every conversion of a growing zone) the element stiffness: the four-operand
contraction done pairwise (``optimize=True``, the code's) against numpy's single loop.

Usage: .venv/bin/python benchmarks/fem_sample.py [--elements 4800 20000] [--repeat 20]
Prints a markdown table of medians.
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from fem_region import materials, mesh
from fem_region.elements import ELEMENTS
from fem_region.region import FemRegion, strain_displacement


def median_time(f, repeat: int) -> float:
    f()  # compile / warm caches
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def region(n_el: int, element: str) -> FemRegion:
    if element == "hex8":  # a plate: 4 elements through, square in plan
        n = max(1, int(np.sqrt(n_el / 4)))
        m = mesh.box(np.linspace(0, 0.02, n + 1), np.linspace(0, 0.02, n + 1), np.linspace(0, 0.002, 5), element)
        D = materials.isotropic(70e9, 0.3)
        return FemRegion(m, ELEMENTS[element], D, 2700.0, 1.0, "selective")
    ny = max(1, int(np.sqrt(n_el / 10)))
    m = mesh.rectangle(np.linspace(0, 10, n_el // ny + 1), np.linspace(0, 1, ny + 1), element)
    return FemRegion(m, ELEMENTS[element], materials.plane_strain(materials.isotropic(70e9, 0.3)), 2700.0, 1.0,
                     "selective")


def naive_stiffness(r: FemRegion) -> np.ndarray:
    ke = 0.0
    for q in r.rules:
        B = strain_displacement(q.dN)
        ke = ke + np.einsum("eqsa,est,eqtb,eq->eab", B, r._masked_D(q.voigt), B, q.dx)
    return ke


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--elements", type=int, nargs="+", default=[4800, 20000])
    ap.add_argument("--repeat", type=int, default=20)
    a = ap.parse_args()
    print("| elements | element | rules | guard [ms] | energy pass [ms] | ratio | stiffness [s] | one loop [s] | ratio |")
    print("|---|---|---|---|---|---|---|---|---|")
    for n in a.elements:
        for element in ("hex8", "quad4"):
            r = region(n, element)
            u = 1e-6 * np.random.default_rng(0).standard_normal((r.n_nodes, r.dim))
            guard = median_time(lambda: r.inverted_elements(u), a.repeat)
            energy = median_time(lambda: r._total_lagrangian_pass(u), a.repeat)
            ke = median_time(r._element_stiffness, 3)
            loop = median_time(lambda: naive_stiffness(r), 1)
            print(f"| {r.n_elements:,} | {element} | {len(r.rules)} | {guard * 1e3:.2f} | {energy * 1e3:.2f} | "
                  f"{energy / guard:.1f} | {ke:.3f} | {loop:.2f} | {loop / ke:.1f} |", flush=True)


if __name__ == "__main__":
    main()
