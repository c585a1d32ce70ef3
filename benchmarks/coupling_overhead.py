"""Coupling overhead of the FEM + DEM clock at about 10^4 particles and 750 interface particles.

Usage: .venv/bin/python benchmarks/coupling_overhead.py [--repeat 3] [--steps 200]
           [--dem yade|liggghts|lammps] [--scale 0.1 1 10] [--process in-process worker]
           [--ranks 1 2]  (MPI ranks of the engine in its worker: lammps only)
Runs coupled_free_flight scaled to a 0.864 m x scale tall lattice (10,729 particles at scale
1, 749 of them in the interface band; particles and interface grow with the scale) with the
engine in-process and in a worker process; prints the medians of the per-step times and of
(interface + orchestrator) / DEM engine time. LAMMPS runs only in its worker; there the
engine's own time is DEM and the socket round trips and shared-memory copies are transport;
--ranks runs it on that many MPI ranks inside its worker.
"""
from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SETS = ["geometry.dem_length=0.04", "geometry.fem_length=0.02", "output.field_frames=0"]


def run(process: str, steps: int, dem: str, scale: float, ranks: int = 1) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "run"
        args = [sys.executable, "-m", "coupling.cli", "run", "coupled_free_flight", "--quiet", "--out", str(out),
                "--set", f"run.steps={steps}", "--set", f"dem.process={process}", "--dem", dem,
                "--set", f"geometry.height={0.864 * scale:g}", "--set", f"dem.ranks={ranks}",
                "--set", f"output.history_every={max(1, steps // 10)}"]  # (the fewest samples a run takes)
        for s in SETS:
            args += ["--set", s]
        subprocess.run(args, cwd=ROOT, check=True)
        return json.loads((out / "summary.json").read_text())


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--dem", default="yade")
    ap.add_argument("--scale", type=float, nargs="+", default=[1.0])
    ap.add_argument("--process", nargs="+", default=["in-process", "worker"])
    ap.add_argument("--ranks", type=int, nargs="+", default=[1])
    a = ap.parse_args()
    print("| engine | process | ranks | particles | interface | DEM [ms/step] | transport [ms/step] | interface [ms/step] "
          "| FEM [ms/step] | overhead ratio |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for process, scale, ranks in ((p, s, n) for s in a.scale for p in a.process for n in a.ranks):
        rows = [run(process, a.steps, a.dem, scale, ranks) for _ in range(a.repeat)]
        med = lambda k: statistics.median(r["timing_s"][k] for r in rows) / a.steps * 1e3
        ratio = statistics.median((r["timing_s"]["interface"] + r["timing_s"]["orchestrator"]) / r["timing_s"]["dem"]
                                  for r in rows)
        c = rows[0]["counts"]
        print(f"| {a.dem} | {process} | {ranks} | {c['particles']:,} | {c['interface_particles']} | {med('dem'):.2f} | "
              f"{med('transport'):.2f} | {med('interface'):.2f} | {med('fem'):.2f} | {ratio:.3f} |",
              flush=True)


if __name__ == "__main__":
    main()
