"""Stability map of seed example 5.3 (rod_impact): the paper's hourglass and penalty settings.

Runs the coarse case (the paper-like mesh, one element per layer) once per setting through
the command line, as a user would, and tabulates what the program did: ran to 0.4 ms, was
refused before the first step (exit 2, the stable-step limit named), or stopped while
running (exit 3, with the guard's diagnosis and the time). The paper's steps 1e-6 s and
1e-7 s are read as "the elements' own stable step" and "a tenth of it" (its mesh is not
given; here the elements allow ~3e-7 s).

    .venv/bin/python benchmarks/rod_impact_stability.py [--out DIR]

writes DIR/stability_map.json and prints a Markdown table (docs/benchmarks.md).
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

# (label, the paper's observation, settings, step: "element" or "element/10")
SETTINGS = [
    ("1 one-point, hourglass control off, penalties 2e12", "unstable: layer separation and hourglass modes",
     {"fem.integration": "reduced", "fem.hourglass": "none", "impactors.rod.penalty": 2e12, "interfaces.table3.penalty": 2e12},
     "element"),
    ("2 one-point + hourglass control, rod penalty 2e10", "rod passes through the plate",
     {"fem.integration": "reduced", "impactors.rod.penalty": 2e10, "interfaces.table3.penalty": 2e12}, "element"),
    ("3 one-point + hourglass control, penalties 2e12", "much better",
     {"fem.integration": "reduced", "impactors.rod.penalty": 2e12, "interfaces.table3.penalty": 2e12}, "element"),
    ("4 one-point + hourglass control, rod 2e14 / layers 2e12", "top layer distorts, fatal hourglassing",
     {"fem.integration": "reduced", "impactors.rod.penalty": 2e14, "interfaces.table3.penalty": 2e12}, "element"),
    ("5 one-point + hourglass control, penalties 2e14, step / 10", "best: runs to 0.4 ms",
     {"fem.integration": "reduced", "impactors.rod.penalty": 2e14, "interfaces.table3.penalty": 2e14}, "element/10"),
    ("6 full integration, penalties 2e14, step / 10", "(not in the paper)",
     {"fem.integration": "full", "impactors.rod.penalty": 2e14, "interfaces.table3.penalty": 2e14}, "element/10"),
    ("7 full integration, penalties 2e12", "(not in the paper)",
     {"fem.integration": "full", "impactors.rod.penalty": 2e12, "interfaces.table3.penalty": 2e12}, "element"),
    ("8 full integration, rod penalty 2e10", "(not in the paper)",
     {"fem.integration": "full", "impactors.rod.penalty": 2e10, "interfaces.table3.penalty": 2e12}, "element"),
]


def element_step() -> float:
    """s, the stable step of the coarse plate's elements alone (0.9 x the estimate)."""
    from coupling.case import load_case
    from coupling.study.assemble import laminate
    from coupling.study.disc import disc_mesh
    from fem_region.elements import ELEMENTS
    from fem_region.region import FemRegion
    import numpy as np
    p = load_case("rod_impact_coarse").parameters
    lam = laminate(p, p["geometry.laminate"])
    m, run, _, _ = disc_mesh(p, lam, core=False)
    C = np.array([lam.C(a) for a in lam.angles])[run]
    return 0.9 * FemRegion(m, ELEMENTS["hex8"], C, lam.ply["rho"], 1.0, "full", "linear").critical_dt()


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    out = args.out or Path(tempfile.mkdtemp(prefix="rod_stability_"))
    out.mkdir(parents=True, exist_ok=True)
    dt0 = element_step()
    rows = []
    for k, (label, paper, settings, step) in enumerate(SETTINGS):
        dt = dt0 if step == "element" else dt0 / 10
        run_dir = out / f"setting_{k + 1}"
        cmd = [str(ROOT / ".venv/bin/femdem"), "run", "rod_impact_coarse", "--out", str(run_dir), "--quiet",
               f"--set=clock.dt={dt:.6g}", *(f"--set={key}={value}" for key, value in settings.items())]
        proc = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
        row = {"setting": label, "paper": paper, "dt": dt, "exit": proc.returncode, **settings}
        summary = run_dir / "summary.json"
        if proc.returncode == 2:
            row.update(outcome="refused before the first step", detail=proc.stderr.strip().splitlines()[-1])
        elif summary.exists():
            s = json.loads(summary.read_text())
            q = s.get("qoi", {})
            row.update(outcome={"ok": "ran to 0.4 ms", "unstable": "stopped"}.get(s["status"], s["status"]),
                       detail=s["message"], t_stop=s["clock"]["t_end"], wall_s=s["timing_s"]["total"],
                       peak_plate_deflection=q.get("peak_plate_deflection"),
                       energy_balance=s["energy"].get("balance_error_rel"))
        else:
            row.update(outcome="error", detail=proc.stderr.strip()[-300:])
        rows.append(row)
        print(f"{label}: {row['outcome']} {row.get('detail', '')[:160]}", file=sys.stderr)
    (out / "stability_map.json").write_text(json.dumps(rows, indent=2))
    print("| setting | paper | step (s) | this program | how it was detected |")
    print("|---|---|---|---|---|")
    for r in rows:
        what = r["outcome"]
        if r["outcome"] == "ran to 0.4 ms":
            what += f", peak deflection {1e3 * r['peak_plate_deflection']:.2f} mm, ledger {r['energy_balance']:.1e}"
        elif r["outcome"] == "stopped":
            what += f" at {1e6 * r['t_stop']:.1f} us"
        detail = r.get("detail", "").replace("|", "/")
        print(f"| {r['setting']} | {r['paper']} | {r['dt']:.3g} | {what} | {detail[:220]} |")
    print(f"\nresults: {out}/stability_map.json", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
