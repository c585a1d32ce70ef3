"""Whole runs of this checkout against an earlier commit, side by side: wall time and sameness.

Usage: .venv/bin/python benchmarks/against_commit.py --base REV [--repeat 1]
           RUN [RUN ...]        RUN = CASE:MODE:ENGINE[:KEY=VALUE,...]

The earlier commit is checked out once into a git worktree (under the system's temporary
directory, removed at the end); each run goes there and here in turn, in fresh processes, with
the same arguments (the same venv: only the project's code differs). Printed per run: the
median wall time of each side and their ratio, the timing buckets of summary.json per side
(medians over the repeats, and the transport's share of the engine's time), and whether
every qoi and every history series is the same to the bit (else the largest relative
difference and its name). Each run is done once on each side before any timing, so
that numba's caches are compiled (a changed kernel recompiles on its first run).
"""
from __future__ import annotations

import argparse
import json
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import h5py
import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def run(tree: Path, case: str, mode: str, engine: str, sets: list[str], out: Path) -> float:
    """One run of ``case`` with the code of ``tree``; returns its wall time (s)."""
    shutil.rmtree(out, ignore_errors=True)
    engine_args = [] if mode == "fem" else ["--dem", engine]  # an all-FEM run takes no engine
    cmd = [sys.executable, "-m", "coupling.cli", "run", case, "--mode", mode, *engine_args, "--out", str(out),
           "--quiet", *(a for s in sets for a in ("--set", s))]
    t0 = time.perf_counter()
    done = subprocess.run(cmd, cwd=tree, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if done.returncode != 0:
        raise SystemExit(f"{tree.name}: {' '.join(cmd[3:])} exited {done.returncode}: {done.stderr.strip()[-400:]}")
    return wall


def sameness(a: Path, b: Path) -> str:
    """'bit-identical', or the largest relative differences of a qoi and of a history series,
    each named (of those both sides have; names on one side only are listed). A series that
    is round-off about zero (a momentum) differs by orders of magnitude relative to itself:
    the qoi's figure is the one to read."""
    worst = {"qoi": (0.0, ""), "history": (0.0, "")}

    def note(kind, k, r):
        if r >= worst[kind][0]:
            worst[kind] = (r, k)
    qa, qb = (json.loads((d / "summary.json").read_text())["qoi"] for d in (a, b))
    for k, v in qa.items():
        w = qb.get(k)
        if isinstance(v, (int, float)) and isinstance(w, (int, float)) and v != w:
            note("qoi", k, abs(v - w) / max(abs(v), 1e-300))
    with h5py.File(a / "history.h5") as fa, h5py.File(b / "history.h5") as fb:
        alone = sorted(set(fa["history"]) ^ set(fb["history"]))
        for k in sorted(set(fa["history"]) & set(fb["history"])):
            x, y = fa["history"][k][()], fb["history"][k][()]
            if x.shape != y.shape:
                return f"history {k}: {x.shape} against {y.shape} samples"
            if not np.array_equal(x, y, equal_nan=True):
                note("history", k, float(np.nanmax(np.abs(x - y) / np.maximum(np.abs(x), 1e-300))))
    parts = [f"{kind} {name} differs by {r:.2e} relative" for kind, (r, name) in worst.items() if name]
    tail = f"; on one side only: {', '.join(alone)}" if alone else ""
    return ("; ".join(parts) or "bit-identical") + tail


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--base", required=True, help="the earlier commit (any git revision)")
    ap.add_argument("--repeat", type=int, default=1, help="runs per side (median wall time)")
    ap.add_argument("runs", nargs="+", metavar="CASE:MODE:ENGINE[:KEY=VALUE,...]")
    args = ap.parse_args()
    scratch = Path(tempfile.mkdtemp(prefix="femdem-against-"))
    base, outs = scratch / "worktree", scratch / "runs"
    subprocess.run(["git", "worktree", "add", "--detach", str(base), args.base], cwd=ROOT, check=True,
                   capture_output=True)
    for venv in (".venv", ".venv-lammps"):  # the LAMMPS worker's environment is found beside the code
        if (ROOT / venv).exists():
            (base / venv).symlink_to(ROOT / venv)
    try:
        for spec in args.runs:
            case, mode, engine, *rest = spec.split(":")
            sets = rest[0].split(",") if rest else []
            for tree in (base, ROOT):  # compiles either side's numba caches, if stale
                run(tree, case, mode, engine, sets, outs / "warm")
            walls, buckets = {"base": [], "this": []}, {"base": [], "this": []}
            for _ in range(args.repeat):
                for side, tree in (("base", base), ("this", ROOT)):
                    walls[side].append(run(tree, case, mode, engine, sets, outs / side))
                    buckets[side].append(json.loads((outs / side / "summary.json").read_text())["timing_s"])
            tb, tt = (statistics.median(walls[s]) for s in ("base", "this"))
            print(f"{spec}: base {tb:.1f} s, this {tt:.1f} s, ratio {tb / tt:.2f}; "
                  f"{sameness(outs / 'base', outs / 'this')}")
            for side in ("base", "this"):  # each bucket's median over the repeats
                runs = buckets[side]
                line = ", ".join(f"{k} {statistics.median(t[k] for t in runs):.2f}" for k in runs[0])
                if all(t.get("dem", 0.0) > 0 for t in runs):
                    line += f"; transport / dem {statistics.median(t['transport'] / t['dem'] for t in runs):.3f}"
                print(f"    {side:4s} {line}")
            sys.stdout.flush()
    finally:
        subprocess.run(["git", "worktree", "remove", "--force", str(base)], cwd=ROOT, capture_output=True)
        shutil.rmtree(scratch, ignore_errors=True)


if __name__ == "__main__":
    main()
