"""What a growing zone's check costs (zone.grow_every; coupling/study/growth.py), side by side.

Part 1, in process, on the coupled model of CASE grown from ZONE (LIGGGHTS), run to T_RUN so
that the impactor presses the zone: one check's parts, medians of --repeat calls,
  - the far field's criterion: the compiled pass (fields.ElementIndex, the code's) against the
    numpy criteria on the centroid strains it replaced (FemIndices, as until session 38);
  - the contact's and the zone's damage reach;
  - the whole check when nothing asks to grow (Growth.__call__ on a check's state).
Part 2, whole runs of the same case in fresh processes (`femdem run`), growth checked at the
history samples only (grow_every = 0) and at every FEM step (1), samples every --history-every
steps, over a span in which the zone does not grow, so that the two runs are the same run and
differ by the checks alone: median wall times of --runs each, their ratio, and the cost per
check (the check's own work, and the loop's stop there: the engine's run is cut at each, and an
engine in a worker process (LAMMPS) or behind YADE's Python API pays a call per run).

Usage: .venv/bin/python benchmarks/growth_check.py [--case beam_impact_coarse] [--zone 3e-3]
           [--t-end 6e-5] [--t-run 3e-5] [--repeat 200] [--runs 3] [--history-every 100]
           [--dem liggghts yade lammps]
"""
from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from coupling.case import load_case
from coupling.simulation import run_clock

ROOT = Path(__file__).resolve().parent.parent


def median_us(f, repeat: int) -> float:
    f()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return 1e6 * float(np.median(times))


def parts(case: str, sets: dict, t_run: float, repeat: int) -> None:
    c = load_case(case, dict(sets, **{"clock.t_end": t_run}))
    study, p = c.scene, c.parameters
    sim = study.build(p, "coupled", "liggghts")
    try:
        run_clock(sim)
        g = study.growth
        region, u = g.built.dyn.region, g.built.clock.u_snapshot
        numpy_index = lambda: np.maximum(*g._indices(region.centroid_strain_stress(u)[0])[::-1])
        assert g(0) is None, "the zone asks to grow here: pick a wider --zone or a shorter --t-run"
        rows = [("far-field criterion, numpy (until session 38)", median_us(numpy_index, repeat)),
                ("far-field criterion, compiled (ElementIndex)", median_us(lambda: g.index(u), repeat)),
                ("contact reach", median_us(g.contact_reach, repeat)),
                ("damage reach", median_us(g.damage_reach, repeat)),
                ("the whole check (nothing grows)", median_us(lambda: g(0), repeat))]
        print(f"{case}: {region.n_elements} elements, {g.built.lattice.n} particles, t = {t_run:g} s")
        print("| part | median [us] |\n|---|---|")
        for name, us in rows:
            print(f"| {name} | {us:.1f} |")
    finally:
        sim.close()


def wall(case: str, dem: str, sets: dict, every: int, out: Path) -> tuple[float, int]:
    """(wall s, clock steps) of one `femdem run`."""
    cmd = [sys.executable, "-m", "coupling.cli", "run", case, "--dem", dem, "--out", str(out), "--quiet",
           *(a for k, v in dict(sets, **{"zone.grow_every": every}).items() for a in ("--set", f"{k}={v}"))]
    t0 = time.perf_counter()
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    t = time.perf_counter() - t0
    if done.returncode:
        raise SystemExit(done.stderr)
    s = json.loads((out / "summary.json").read_text())
    assert s["qoi"]["zone_conversions"] == 0, "the zone grew: the runs would differ by more than their checks"
    return t, int(s["clock"]["steps"])


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--case", default="beam_impact_coarse")
    ap.add_argument("--zone", type=float, default=3e-3)
    ap.add_argument("--t-end", type=float, default=6e-5)
    ap.add_argument("--t-run", type=float, default=3e-5)
    ap.add_argument("--repeat", type=int, default=200)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--history-every", type=int, default=100, help="steps between history samples (both runs)")
    ap.add_argument("--dem", nargs="+", default=["liggghts", "yade", "lammps"])
    a = ap.parse_args()
    sets = {"zone.grow": "true", "zone.half_width": a.zone}
    parts(a.case, {"zone.grow": True, "zone.half_width": a.zone}, a.t_run, a.repeat)
    sets.update({"clock.t_end": a.t_end, "output.history_every": a.history_every})
    print(f"\nwhole runs, {a.case} from {a.zone * 1e3:g} mm to {a.t_end:g} s (a sample every {a.history_every} FEM "
          f"steps), medians of {a.runs}:")
    print("| engine | FEM steps | checked at the samples only [s] | at every FEM step [s] | ratio | per check [us] |")
    print("|---|---|---|---|---|---|")
    for dem in a.dem:
        times: dict[int, list[float]] = {0: [], 1: []}
        steps = 0
        with tempfile.TemporaryDirectory() as tmp:
            for r in range(a.runs + 1):  # the first round compiles numba's caches: not counted
                for every in times:
                    t, steps = wall(a.case, dem, sets, every, Path(tmp) / f"run-{every}-{r}")
                    if r:
                        times[every].append(t)
        t0, t1 = statistics.median(times[0]), statistics.median(times[1])
        checks = steps - steps // a.history_every  # the checks that are no sample's
        print(f"| {dem} | {steps} | {t0:.2f} | {t1:.2f} | {t1 / t0:.3f} | {1e6 * (t1 - t0) / checks:.0f} |")


if __name__ == "__main__":
    main()
