"""DEM steps per second through the adapter next to YADE running the same scene on its own.

Usage: .venv/bin/python benchmarks/dem_throughput.py [--sizes 1000 10000 100000] [--repeat 3]
Scene: a simple cubic bonded block (axial bonds, linear elastic), built once through the
adapter; "adapter" steps with YadeBackend.advance (coupling hook included, empty), "YADE
alone" removes the hook and runs O.run(n, True). One OpenMP thread unless OMP_NUM_THREADS is set.
"""
from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from dem_region import packing
from dem_region.backends.yade import YadeBackend
from dem_region.scene import DemScene


def block(n: int) -> DemScene:
    side = round(n ** (1 / 3))
    r = 0.001
    x = packing.simple_cubic((0, 0, 0), ((side - 1) * 2 * r,) * 3, r)
    bonds = packing.neighbour_bonds(x, r)
    v = np.random.default_rng(0).normal(size=x.shape) * 1e-3
    return DemScene(x, r, 2000.0, bonds, kn=1e6, ks=0.0, velocity=v)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", type=int, nargs="+", default=[1000, 10000, 100000])
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    print("| particles | bonds | adapter [ms/step] | YADE alone [ms/step] | adapter / alone | particle-steps/s (adapter) |")
    print("|---|---|---|---|---|---|")
    for n in a.sizes:
        scene = block(n)
        eng = YadeBackend()
        eng.build(scene)
        eng.set_dt(0.5 * eng.critical_dt())
        eng.start(None)
        steps = max(20, int(2e6 / scene.n))
        ad, alone = [], []
        for _ in range(a.repeat):
            t0 = time.perf_counter()
            for _ in range(steps):
                eng.advance(None)
            ad.append((time.perf_counter() - t0) / steps)
        hook = eng.O.engines[-1]
        eng.O.engines = eng.O.engines[:-1]  # YADE on its own: no coupling hook
        for _ in range(a.repeat):
            t0 = time.perf_counter()
            eng.O.run(steps, True)
            alone.append((time.perf_counter() - t0) / steps)
        eng.O.engines = eng.O.engines + [hook]
        m_ad, m_al = statistics.median(ad), statistics.median(alone)
        print(f"| {scene.n:,} | {len(scene.bonds):,} | {m_ad * 1e3:.3f} | {m_al * 1e3:.3f} | {m_ad / m_al:.3f} | "
              f"{scene.n / m_ad:.3g} |", flush=True)
        eng.finalize()


if __name__ == "__main__":
    main()
