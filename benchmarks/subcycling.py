"""Subcycling: wall time and accuracy against the substep count, with and without the
interface band's elements among the fast forces (coupling/participants/clock.py), side by side.

Usage: .venv/bin/python benchmarks/subcycling.py [--case panel_buckling_coarse]
           [--set clock.t_end=3e-3 ...] [--substeps 1 2 3] [--dem liggghts] [--out DIR]

Each setting is one run of ``femdem run`` in this process (the ablation switches
CoupledClock.fast_band off), in the order given. Reported per run: status (an impulse
resonance stops with exit 3 on the energy guard), the energy balance error, wall time, the
FEM and engine buckets, and every qoi's relative difference from the m = 1 run (the
monolithic-step reference of the same case). Writes subcycling.json.
"""
from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", default="panel_buckling_coarse")
    ap.add_argument("--set", action="append", default=[], dest="sets")
    ap.add_argument("--substeps", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--dem", default="liggghts")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    from coupling.case import load_case
    from coupling.participants.clock import CoupledClock
    from coupling.params import parse_set
    from coupling.run import execute
    out = Path(a.out or tempfile.mkdtemp(prefix="femdem-subcycling-"))
    rows = []
    for band in (True, False):
        for m in a.substeps:
            if m == 1 and not band:
                continue  # the same step: the band only matters with m > 1
            CoupledClock.fast_band = band
            case = load_case(a.case, parse_set(a.sets + [f"clock.substeps={m}"]))
            _, _, s = execute(case, "coupled", a.dem, out / f"m{m}-{'band' if band else 'noband'}", quiet=True)
            rows.append({"substeps": m, "fast_band": band, "status": s["status"], "message": s["message"][:120],
                         "balance_error_rel": s["energy"]["balance_error_rel"], "wall_s": s["timing_s"]["total"],
                         "fem_s": s["timing_s"]["fem"], "dem_s": s["timing_s"]["dem"], "steps": s["clock"]["steps"],
                         "qoi": s["qoi"]})
            r = rows[-1]
            print(f"m = {m:2d} band {'on ' if band else 'off'}: {r['status']:8s} energy error {r['balance_error_rel']:.2e}"
                  f"  wall {r['wall_s']:7.1f} s (fem {r['fem_s']:6.1f}, dem {r['dem_s']:6.1f}), {r['steps']} FEM steps"
                  + (f"  [{r['message']}]" if r["status"] != "ok" else ""), flush=True)
    CoupledClock.fast_band = True
    ref = next(r for r in rows if r["substeps"] == 1)["qoi"] if 1 in a.substeps else {}
    for r in rows:
        r["qoi_rel_diff_vs_m1"] = {k: abs(v - ref[k]) / abs(ref[k]) for k, v in r["qoi"].items()
                                   if k in ref and isinstance(v, (int, float)) and ref[k] and v == v
                                   and "diff" not in k and not k.endswith("_rel")}  # (errors already)
        if r["status"] == "ok" and r["qoi_rel_diff_vs_m1"]:
            worst = max(r["qoi_rel_diff_vs_m1"].items(), key=lambda kv: kv[1])
            print(f"m = {r['substeps']} band {r['fast_band']}: largest qoi difference from m = 1: {worst[0]} {worst[1]:.2e}")
    (out / "subcycling.json").write_text(json.dumps(rows, indent=1, default=str))
    print(f"results: {out / 'subcycling.json'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
