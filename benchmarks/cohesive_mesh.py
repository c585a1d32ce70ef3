"""Mesh convergence of the all-FEM delamination specimens (issue #24): the peak load against its
closed form as the node spacing along the crack plane shrinks, with the cohesive zone's length
in elements as the axis.

The strengths are the case's own (interface.cohesive_zone_bonds = 0: not lowered to the mesh),
so the cohesive zone has one physical length, the slender-arm estimate of
delamination.cohesive_zone_length (mode I for the DCB, mode II for the ENF, the shorter of the
two for the mixed-mode SLB, with the strengths its law uses); each run meshes it
with N elements (mesh.element_length = l_cz / N). Spacings whose first element could not start
softening (Gc below tau^2 / (2 K)) are refused by the case and reported as such. With
--lowered the case keeps its rule instead (interface.cohesive_zone_bonds: strengths lowered so
that Rice's zone spans that many elements, Turon et al. 2007), on the same element lengths.

Usage: .venv/bin/python benchmarks/cohesive_mesh.py [--case dcb_coarse|enf_coarse|mixed_mode_coarse]
           [--n 2,4,8,16,32] [--lowered]
Prints a markdown table (N, element length, peak load, its closed form, error, wall time, steps).
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))


def zone_length(case: str) -> float:
    """m, the case's cohesive zone (slender-arm estimate) with its given strengths."""
    from coupling.case import load_case
    from coupling.scenes import delamination as dl
    p = load_case(case).parameters
    GIc, GIIc, Z0, R0 = (p[f"interface.{k}"] for k in ("GIc", "GIIc", "Z0", "R0"))
    if case.startswith("dcb"):
        return dl.cohesive_zone_length(p, GIc, Z0, "I")
    if case.startswith("enf"):
        return dl.cohesive_zone_length(p, GIIc, R0, "II")
    # mixed mode (the SLB): the strengths the law uses, and the shorter of the two modes' zones
    if p.get("interface.consistent_strengths", False):
        Z0, R0 = dl.consistent(Z0, R0, GIc, GIIc)
    return min(dl.cohesive_zone_length(p, GIc, Z0, "I"), dl.cohesive_zone_length(p, GIIc, R0, "II"))


def run(case: str, length: float, out: Path, lowered: bool) -> tuple[dict | None, str, float]:
    t0 = time.perf_counter()
    keep = [] if lowered else ["--set=interface.cohesive_zone_bonds=0"]
    r = subprocess.run([sys.executable, "-m", "coupling.cli", "run", case, "--mode", "fem", "--quiet",
                        f"--set=mesh.element_length={length}", *keep, "--out", str(out)],
                       cwd=ROOT, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    summary = out / "summary.json"
    return (json.loads(summary.read_text()) if r.returncode == 0 and summary.exists() else None,
            r.stderr.strip().splitlines()[-1] if r.returncode else "", wall)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", default="dcb_coarse")
    ap.add_argument("--n", default="2,4,8,16,32", help="elements in the cohesive zone")
    ap.add_argument("--lowered", action="store_true", help="the case's strength rule instead of its given strengths")
    a = ap.parse_args()
    l_cz = zone_length(a.case)
    how = "strengths lowered by the case's rule" if a.lowered else "given strengths"
    print(f"{a.case} --mode fem, {how}; cohesive zone of the given strengths (slender-arm estimate) "
          f"{1e3 * l_cz:.2f} mm\n")
    print("| N = l_cz / element | element (mm) | peak load (N) | closed form (N) | error | wall (s) | steps |")
    print("|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for n in (int(v) for v in a.n.split(",")):
            length = l_cz / n
            s, err, wall = run(a.case, length, Path(tmp) / f"n{n}", a.lowered)
            if s is None:
                print(f"| {n} | {1e3 * length:.3f} | refused: {err} | | | {wall:.1f} | |")
                continue
            c = s["checks"]["peak_load"]
            print(f"| {n} | {1e3 * length:.3f} | {c['value']:.1f} | {c['reference']:.1f} | "
                  f"{100 * (c['value'] / c['reference'] - 1):+.2f} % | {wall:.1f} | {s['clock']['steps']} |", flush=True)


if __name__ == "__main__":
    main()
