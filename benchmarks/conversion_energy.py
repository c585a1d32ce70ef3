"""A growing zone's conversions, each by the ledger's parts: where the stored energy jumps.

Usage: .venv/bin/python benchmarks/conversion_energy.py CASE ENGINE [KEY=VALUE ...]
e.g.   .venv/bin/python benchmarks/conversion_energy.py beam_impact_coarse liggghts \\
           impactors.cylinder.velocity=12 zone.grow=true zone.half_width=3e-3 zone.grow_at=0.12 clock.t_end=3e-5

For each conversion: its time, the grown half width, the jump of the stored energy (of the
total), and each part of the ledger at the old model's last snapshot and the new model's first:
the FEM's kinetic (the snapshot's on-step velocities) and internal energy, the engine's
particles' kinetic and elastic energy, the tie's, and each hosted model's (law bonds,
impactors: kinetic + internal). The clock's snapshot is wrapped to keep its parts.
"""
from __future__ import annotations

import sys

import numpy as np

from coupling.case import load_case
from coupling.params import parse_set
from coupling.participants.clock import CoupledClock
from coupling.simulation import run_clock

_snapshot = CoupledClock._snapshot


def _snapshot_with_parts(self, f_fast, a_slow):
    _snapshot(self, f_fast, a_slow)
    v = self.v_snapshot
    d = self.dem.energies()
    self.parts = {"FEM kinetic": 0.5 * float(np.einsum("n,ni,ni->", self.fem.m, v, v)),
                  "FEM internal": self.fem.energies()["internal"], "particles kinetic": d["kinetic"],
                  "engine elastic": d["elastic"], "tie": self.tie.energy()}
    for k, m in enumerate(self.models):
        e = m.energies()
        self.parts[f"model {k} ({type(m).__name__})"] = e.get("kinetic", 0.0) + e.get("internal", 0.0)


def main(case: str, engine: str, *sets: str) -> None:
    CoupledClock._snapshot = _snapshot_with_parts
    c = load_case(case, parse_set(list(sets)))
    sim = c.scene.build(c.parameters, "coupled", engine)
    growth = sim.growth
    convert = growth.convert

    def reported(half_width, step):
        before = dict(growth.built.clock.parts)
        new = convert(half_width, step)
        after = growth.built.clock.parts
        t, w, jump, _ = growth.events[-1]
        print(f"conversion at {t * 1e6:.2f} us to {w * 1e3:.2f} mm: stored energy jump {jump:.3g} of the total")
        for k in sorted(set(before) | set(after)):
            b, a = before.get(k, 0.0), after.get(k, 0.0)
            print(f"    {k:34s} {b:12.6g} -> {a:12.6g} J   ({a - b:+.4g} J)")
        return new

    growth.convert = reported
    run_clock(sim)["simulation"].close()


if __name__ == "__main__":
    main(*sys.argv[1:])
