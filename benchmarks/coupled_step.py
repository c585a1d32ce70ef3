"""The coupled step's cost: the law kernels alone, and per-stage times of real coupled runs.

Usage: .venv/bin/python benchmarks/coupled_step.py [--bonds 1e3 1e4 1e5 1e6] [--steps 20]
           [--repeat 5] [--runs beam_impact_coarse beam_impact] [--dem liggghts yade lammps]
           [--run-set clock.t_end=2e-4] [--ranks 1 2] [--skip-runs] [--skip-kernels] [--handshake]
           [--parallel-from BONDS]

1. Kernels: the 3D quarter beam's lattice (beam_impact_3d: Hoffman ply bonds and Hashin
   interface bonds with two tangents' slope terms), widened and lengthened until each family
   has about the requested number of bonds (the interface family on a lattice of alternating
   0 / 90 rows: families()), in a deformed state (random displacements of
   --noise x the spacing, 1e-4 by default: elastic, the state of most bonds most of the time;
   at 1e-3 many bonds sit at initiation and re-test it every step); ns per bond-step of the fused kernels
   on 1 and 2 threads and of the reference path (LawBonds.apply_reference: vectorised numpy,
   today's path before the kernels) on the same bonds, side by side, medians of --repeat;
   only the law step is timed, not the harness's move of the positions.
2. Runs: each case coupled on each engine (a fresh process each, --set output to a minimum),
   ms per engine step of each timing bucket of summary.json (dem = the engine's own time,
   models = the coupling layer's laws with their transfer, interface, fem, transport, io,
   orchestrator), and ns per law bond and step of the models bucket. LAMMPS on each of --ranks
   MPI ranks: the law bonds each rank evaluates (those of the atoms it owns); every rank still
   gathers every atom each step (the worker's arrays are full copies), which the line says.
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

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))


class Arrays:
    """Positions and forces of every particle; a particle's row is its id (what ModelStep is)."""

    def __init__(self, x):
        self.x, self.f = x, np.zeros_like(x)

    def rows_of(self, ids):
        return ids

    def positions_of(self, ids):
        return self.x[ids]

    def add_forces(self, ids, F):
        np.add.at(self.f, ids, F)


def families(target_bonds: float, family: str = "ply"):
    """(ply LawBonds, interface LawBonds, reference positions) of a beam_impact_3d lattice
    grown until ``family`` ("ply" or "interface") has about target_bonds bonds. The interface
    family is timed on a lattice of 0 / 90 rows alternating ([0_2/90_2]4 at two plies per row:
    seven interfaces per column, one interface bond per seven ply bonds, against one per 28 in
    the seed's [0_6/90_4/0_6]), so that 10^6 interface bonds fit in memory."""
    from coupling.case import load_case
    from coupling.study.assemble import particle_zone
    d = 0.6e-3  # two 0.15 mm plies per particle row
    layup, per_column = {"ply": ("[0_6/90_4/0_6]", 1.2e5 / (41 * 41)), "interface": ("[0_2/90_2]4", 28.0)}[family]
    columns = max(4, int(np.sqrt(target_bonds / per_column)))
    width = 2 * columns * d
    # a lattice to time, not a study: its width, span and layup lie past the case's verified [ranges]
    p = {**load_case("beam_impact_3d").parameters, "geometry.width": width, "geometry.span": max(0.1, 4 * columns * d),
         "laminates.beam.layup": layup}
    block, _, intra, inter = particle_zone(p, (columns - 1) * d, tied=False, clamped=True)
    return intra, inter, block.x


def time_family(bonds, X, steps: int, repeat: int, threads: list[int], noise: float) -> dict:
    """Median ns per bond-step: fused on each thread count, reference."""
    import numba
    rng = np.random.default_rng(0)
    xs = [X + rng.normal(size=X.shape) * noise * 0.6e-3 for _ in range(steps)]
    nb = len(bonds.pairs)
    out = {"bonds": nb}
    state = bonds.checkpoint_state()
    for label, n_threads in [(f"fused_{t}", t) for t in threads] + [("reference", None)]:
        times = []
        for _ in range(repeat):
            bonds.restore_state(state)
            a = Arrays(xs[0].copy())
            if n_threads:
                numba.set_num_threads(n_threads)
                bonds.apply(a, 1e-8)  # compile / bind outside the timing
            spent = 0.0
            for x in xs:
                a.x[:] = x  # the engine's move: not the law step's time
                t0 = time.perf_counter()
                bonds.apply(a, 1e-8) if n_threads else bonds.apply_reference(a, 1e-8)
                spent += time.perf_counter() - t0
            times.append(spent / (steps * nb) * 1e9)
        out[label] = statistics.median(times)
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    return out


def yade_transfer(n: int = 1296, repeat: int = 200) -> dict:
    """us per particle of each path between numpy and YADE (a scene of n spheres; the adapter's
    paths are the fast ones): positions read body by body and through coordsAndDisplacements,
    forces added through a Vector3 and from a list, and YADE's own step for comparison."""
    from dem_region.backends.yade import _import_yade, _rows
    yade, w = _import_yade()
    O, u = yade.O, yade.utils
    O.reset()
    O.bodies.append([u.sphere((i * 1e-3, (i % 7) * 1e-3, 0), 4e-4) for i in range(n)])
    O.engines = [w.ForceResetter(), w.InsertionSortCollider([w.Bo1_Sphere_Aabb()]),
                 w.InteractionLoop([w.Ig2_Sphere_Sphere_ScGeom()], [w.Ip2_FrictMat_FrictMat_FrictPhys()],
                                   [w.Law2_ScGeom_FrictPhys_CundallStrack()]), w.NewtonIntegrator()]
    O.dt = 1e-9
    O.step()
    states, ids = [b.state for b in O.bodies], list(range(n))
    coords = yade._utils.coordsAndDisplacements
    F = np.random.default_rng(0).normal(size=(n, 3)).tolist()
    V3, add = yade.Vector3, O.forces.addF
    paths = {
        "read, each body's state": lambda: _rows(states[i].pos for i in ids),
        "read, coordsAndDisplacements x 3": lambda: np.column_stack([np.asarray(coords(k)[0]) for k in range(3)]),
        "add force, Vector3": lambda: [add(i, V3(*f)) for i, f in zip(ids, F)],
        "add force, list": lambda: [add(i, f) for i, f in zip(ids, F)],
        "YADE step (for comparison)": O.step,
    }
    out = {}
    for name, fn in paths.items():
        fn()
        t = []
        for _ in range(5):
            t0 = time.perf_counter()
            for _ in range(repeat):
                fn()
            t.append((time.perf_counter() - t0) / (repeat * n) * 1e6)
        out[name] = statistics.median(t)
    O.reset()
    return out


def _await(bell, which: int, k: int, wait) -> None:
    """Wait (Backoff ``wait``) until the doorbell's counter ``which`` reaches k."""
    while not bell.rung(which, k):
        wait()
    wait.reset()


def _echo(name: str, rounds: int) -> None:
    """The worker's side of handshake(): each advance one engine step with one hook, no work."""
    from dem_region.doorbell import ADVANCE, DONE, GO, HOOK, Backoff, Doorbell
    bell, wait = Doorbell(name), Backoff()
    for k in range(1, rounds + 1):
        _await(bell, ADVANCE, k, wait)
        bell.ring(HOOK, k)
        _await(bell, GO, k, wait)
        bell.ring(DONE, k)
    bell.close()


def handshake(rounds: int = 20000, repeat: int = 5) -> list[float]:
    """us per engine step of the worker handshake alone (dem_region.doorbell: advance, hook, go,
    done; both sides spinning, no work between): the floor of the transport bucket of an engine
    in a worker that steps once per clock step with the orchestrator's hook."""
    from dem_region.doorbell import ADVANCE, DONE, GO, HOOK, Backoff, Doorbell
    out = []
    for _ in range(repeat):
        bell = Doorbell()
        # its own interpreter (as the engine's worker is): a child of multiprocessing would share
        # this one's resource tracker, which the attached side's unregistering confuses
        child = subprocess.Popen([sys.executable, "-c", f"import sys; sys.path.insert(0, {str(ROOT)!r}); "
                                  f"from benchmarks.coupled_step import _echo; _echo({bell.name!r}, {rounds})"])
        wait = Backoff()
        try:
            t0 = None
            for k in range(1, rounds + 1):
                if k == 101:  # past the child's start
                    t0 = time.perf_counter()
                bell.ring(ADVANCE, k)
                _await(bell, HOOK, k, wait)
                bell.ring(GO, k)
                _await(bell, DONE, k, wait)
            out.append((time.perf_counter() - t0) / (rounds - 100) * 1e6)
            child.wait(timeout=30)
        finally:
            if child.poll() is None:
                child.kill()
            bell.close()
    return out


def run_case(case: str, dem: str, sets: list[str]) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "run"
        args = [sys.executable, "-m", "coupling.cli", "run", case, "--quiet", "--out", str(out), "--dem", dem,
                "--mode", "coupled", "--set", "output.field_frames=0"]
        for item in sets:
            args += ["--set", item]
        t0 = time.perf_counter()
        subprocess.run(args, cwd=ROOT, check=True)
        wall = time.perf_counter() - t0
        s = json.loads((out / "summary.json").read_text())
    steps = s["clock"]["steps"] * max(1, s["clock"].get("substeps", 1))
    law_bonds = s["counts"].get("law_bonds") or 0
    row = {"case": case, "dem": dem, "wall_s": wall, "engine_steps": steps, "law_bonds": law_bonds,
           "per_rank": s["counts"].get("law_bonds_per_rank")}
    for k, v in s["timing_s"].items():
        row[f"{k}_ms"] = 1e3 * v / steps
    if law_bonds:
        row["models_ns_per_bond_step"] = 1e9 * s["timing_s"]["models"] / (steps * law_bonds)
    return row


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bonds", type=float, nargs="+", default=[1e3, 1e4, 1e5, 1e6])
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--noise", type=float, default=1e-4, help="random displacements / spacing")
    ap.add_argument("--parallel-from", type=int, default=None, metavar="BONDS",
                    help="families of this many bonds or more run the parallel build (law_kernels.PARALLEL_BONDS; "
                         "0: every family, to find where it pays)")
    ap.add_argument("--runs", nargs="+", default=["beam_impact_coarse"])
    ap.add_argument("--dem", nargs="+", default=["liggghts", "yade", "lammps"])
    ap.add_argument("--run-set", action="append", default=[], metavar="KEY=VALUE",
                    help="for the runs, e.g. clock.t_end=2e-4 (ms per step do not need the whole run)")
    ap.add_argument("--ranks", type=int, nargs="+", default=[1],
                    help="LAMMPS runs on each of these MPI rank counts (dem.ranks)")
    ap.add_argument("--skip-runs", action="store_true")
    ap.add_argument("--yade-transfer", action="store_true",
                    help="only the paths between numpy and YADE, us per particle (YADE owns this process's OpenMP)")
    ap.add_argument("--skip-kernels", action="store_true")
    ap.add_argument("--handshake", action="store_true",
                    help="only the worker handshake between two processes, us per engine step")
    a = ap.parse_args()
    if a.parallel_from is not None:
        from physics import law_kernels
        law_kernels.PARALLEL_BONDS = a.parallel_from
    if a.handshake:
        us = handshake(repeat=a.repeat)
        print(f"worker handshake alone: {statistics.median(us):.2f} us per engine step (median of {a.repeat}: "
              + ", ".join(f"{u:.2f}" for u in us) + ")")
        return
    if a.yade_transfer:
        for name, us in yade_transfer().items():
            print(f"{name:<36}{us:8.2f} us per particle")
        return
    if not a.skip_kernels:
        print(f"law kernels alone, ns per bond-step (median of {a.repeat}; noise {a.noise:g} x spacing)")
        print(f"{'family':<14}{'bonds':>10}" + "".join(f"{f'fused {t} thr':>14}" for t in a.threads)
              + f"{'reference':>12}{'ratio':>8}")
        for target in a.bonds:
            steps = max(3, int(a.steps * min(1.0, 1e5 / target)))
            for name, family in (("ply (Hoffman)", "ply"), ("interface 3D", "interface")):
                intra, inter, X = families(target, family)
                b = intra if family == "ply" else inter
                r = time_family(b, X, steps, a.repeat, a.threads, a.noise)
                best = min(r[f"fused_{t}"] for t in a.threads)
                print(f"{name:<14}{r['bonds']:>10d}" + "".join(f"{r[f'fused_{t}']:>14.1f}" for t in a.threads)
                      + f"{r['reference']:>12.1f}{r['reference'] / best:>7.1f}x", flush=True)
    if not a.skip_runs:
        print("\ncoupled runs, ms per engine step by timing bucket")
        for case in a.runs:
            for dem in a.dem:
                for ranks in (a.ranks if dem == "lammps" else [1]):
                    sets = a.run_set + ([f"dem.ranks={ranks}"] if ranks > 1 else [])
                    r = run_case(case, dem, sets)
                    buckets = " ".join(f"{k[:-3]} {v:.3f}" for k, v in r.items() if k.endswith("_ms"))
                    extra = f"; models {r['models_ns_per_bond_step']:.0f} ns/bond-step" if "models_ns_per_bond_step" in r else ""
                    on = f"{dem} on {ranks} ranks" if ranks > 1 else dem
                    print(f"{case} on {on}: wall {r['wall_s']:.1f} s, {r['engine_steps']} engine steps, "
                          f"{r['law_bonds']} law bonds; {buckets}{extra}", flush=True)
                    if ranks > 1:
                        print(f"    law bonds per rank {r['per_rank']} (each rank those of the atoms it owns); "
                              "every rank still gathers every atom's x, v and f each step (full copies)", flush=True)


if __name__ == "__main__":
    main()
