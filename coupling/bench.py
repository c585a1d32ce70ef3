"""``femdem bench``: speed against error over a sweep of parameters, with a cached reference.

Every sweep point is a normal run (its own run directory under the bench directory); its
error is the relative difference of each quantity of interest from the reference run (by
default the same case in ``--mode dem``, the whole domain as particles, or a run with
``--reference-set`` overrides, e.g. the finest setting). References are cached by their
resolved parameters, mode and engine, so sweeps reuse them. Writes speed_error.json and
speed_error.png (wall time against error, the Pareto front marked).
"""
from __future__ import annotations

import hashlib
import itertools
import json
import os
from pathlib import Path

import numpy as np

from .case import load_case
from .params import CaseError, parse_set
from .run import execute


def _cache_dir() -> Path:
    from . import CACHE
    return Path(os.environ.get("FEMDEM_CACHE_DIR") or CACHE) / "references"


def _key(parameters: dict, mode: str, dem: str) -> str:
    blob = json.dumps({"p": parameters, "mode": mode, "dem": dem}, sort_keys=True, default=str)
    return hashlib.sha1(blob.encode()).hexdigest()[:20]


def parse_sweep(items: list[str]) -> dict[str, list[str]]:
    """["clock.substeps=1,2,4", ...] -> {"clock.substeps": ["1", "2", "4"]}."""
    out = {}
    for item in items:
        key, sep, values = item.partition("=")
        values = [v.strip() for v in values.split(",")]
        if not sep or not key.strip() or not all(values):
            raise CaseError(f"--sweep {item!r}: expected key=v1,v2,... with a dotted key and no empty value")
        if key.strip() in out:
            raise CaseError(f"--sweep {key.strip()}: given twice; allowed: one --sweep per key")
        out[key.strip()] = values
    return out


def reference(case_name: str, overrides: dict, mode: str, dem: str, out: Path) -> tuple[dict, bool]:
    """The reference summary (from the cache when the same run was made before)."""
    case = load_case(case_name, overrides)
    path = _cache_dir() / f"{_key(case.parameters, mode, dem)}.json"
    if path.exists():
        return json.loads(path.read_text()), True
    code, _, summary = execute(case, mode, dem, out, quiet=True)
    if code:
        raise CaseError(f"reference run ({mode}) did not finish: {summary['message']}")
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(summary, default=str))
    os.replace(tmp, path)
    return summary, False


def pareto(times: np.ndarray, errors: np.ndarray) -> np.ndarray:
    """Indices of the points no other point beats in both wall time and error."""
    idx = []
    for i in range(len(times)):
        dominated = np.any((times <= times[i]) & (errors <= errors[i]) & ((times < times[i]) | (errors < errors[i])))
        if not dominated:
            idx.append(i)
    return np.array(idx, int)


def sweep_points(case_name: str, sweep: dict[str, list[str]], base: dict, ref_mode: str, ref_set: dict, dem: str,
           mode: str) -> list[tuple[str, dict]]:
    """(engine, overrides) of every sweep point, each loaded and checked (and the reference's)
    before any runs: a bad value in the last point must not cost the first ones' time."""
    from .case import ENGINES, MODES, refuse_ineffective
    engines = dem.split(",")
    bad = [e for e in engines if e not in ENGINES]
    if bad or len(set(engines)) < len(engines):
        raise CaseError(f"--dem {dem}: allowed one or more different engines of {', '.join(ENGINES)}, "
                        "separated by commas")
    for flag, m in (("--mode", mode), ("--reference-mode", ref_mode)):
        if m not in MODES:
            raise CaseError(f"{flag} {m}: allowed {', '.join(MODES)}")
    keys = list(sweep)
    todo = [(ref_mode, engines[0], {**base, **ref_set})]
    todo += [(mode, e, {**base, **dict(zip(keys, combo))})
             for e, combo in itertools.product(engines, itertools.product(*(sweep[k] for k in keys)))]
    for k, (m, engine, sets) in enumerate(todo):
        case = load_case(case_name, sets)
        if m not in case.scene.MODES:
            raise CaseError(f"--mode {m}: case {case.name} supports {', '.join(case.scene.MODES)}")
        refuse_ineffective(case, m, engine if m != "fem" else None, reference=k == 0)
    return [(e, s) for _, e, s in todo[1:]]


def compared_qoi(p: dict, qoi: dict, ref_qoi: dict) -> list[str]:
    """The qoi a sweep point is compared on by default: those both runs report, except error
    measures (_rel), the model's size (a cost) and the zone-edge probes' (a diagnostic of the
    coupled zone: in an all-DEM reference it reads the damage where the case's zone would end)."""
    zone_edge = {k.split(".")[1] for k, v in p.items()
                 if k.startswith("probes.") and k.endswith(".kind") and v == "zone_edge_damage"}
    return [q for q in qoi if q in ref_qoi and not q.endswith("_rel") and not q.startswith("model_size")
            and q not in zone_edge]


def bench(case_name: str, sweep: dict[str, list[str]], base: dict, ref_mode: str, ref_set: dict, dem: str,
          mode: str, out: Path, qoi: list[str] | None = None) -> dict:
    """Run the sweep; dem: one engine or several separated by commas (an axis of the sweep:
    one curve each; the reference runs on the first); qoi: names compared with the reference
    (default: compared_qoi)."""
    sweep_points(case_name, sweep, base, ref_mode, ref_set, dem, mode)
    out.mkdir(parents=True, exist_ok=True)
    engines = dem.split(",")
    if mode != "fem" or ref_mode != "fem":  # import the engine once, so no run pays for it
        from dem_region.backends import make_backend
        make_backend("yade").finalize() if "yade" in engines else None
    ref, cached = reference(case_name, {**base, **ref_set}, ref_mode, engines[0], out / "reference")
    unknown = [q for q in qoi or [] if q not in ref["qoi"]]
    if unknown:  # known only once the reference has run: refused before any sweep point runs
        raise CaseError(f"--qoi {unknown[0]}: not a quantity of this case; allowed: {', '.join(ref['qoi'])}")
    keys = list(sweep)
    points = []
    for engine, combo in itertools.product(engines, itertools.product(*(sweep[k] for k in keys))):
        sets = {**base, **dict(zip(keys, combo))}
        case = load_case(case_name, sets)
        name = "_".join(f"{k.split('.')[-1]}{v}" for k, v in zip(keys, combo)) or "base"
        name = f"{engine}_{name}" if len(engines) > 1 else name
        code, _, s = execute(case, mode, engine, out / name, quiet=True)
        names = qoi or compared_qoi(case.parameters, s["qoi"], ref["qoi"])
        errors = {q: abs(s["qoi"][q] - ref["qoi"][q]) / abs(ref["qoi"][q]) for q in names
                  if q in s["qoi"] and q in ref["qoi"] and ref["qoi"][q]}
        points.append({"setting": dict(zip(keys, combo)), "dem": engine, "status": s["status"], "wall_s": s["timing_s"]["total"],
                       "timing_s": s["timing_s"], "qoi": s["qoi"], "rel_error": errors,
                       "max_rel_error": max(errors.values()) if errors else None})
    ok = [p for p in points if p["status"] == "ok" and p["max_rel_error"] is not None]
    front = pareto(np.array([p["wall_s"] for p in ok]), np.array([p["max_rel_error"] for p in ok])) if ok else []
    for i in front:
        ok[i]["pareto"] = True
    result = {"case": case_name, "mode": mode, "dem": dem, "reference": {"mode": ref_mode, "set": ref_set,
              "cached": cached, "wall_s": ref["timing_s"]["total"], "qoi": ref["qoi"]}, "points": points}
    tmp = out / "speed_error.json.tmp"
    tmp.write_text(json.dumps(result, indent=1, default=str))
    os.replace(tmp, out / "speed_error.json")
    _plot(result, out / "speed_error.png")
    return result


def _plot(result: dict, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    ok = [p for p in result["points"] if p["status"] == "ok" and p["max_rel_error"]]
    fig, ax = plt.subplots(figsize=(6, 4))
    for engine in dict.fromkeys(p.get("dem", result["dem"]) for p in ok):  # one curve per engine
        mine = sorted((p for p in ok if p.get("dem", result["dem"]) == engine), key=lambda p: p["wall_s"])
        t = [p["wall_s"] for p in mine]
        e = [p["max_rel_error"] for p in mine]
        ax.loglog(t, e, "o-", lw=0.6, label=f"{result['case']} ({engine})")
        for p, ti, ei in zip(mine, t, e):
            ax.annotate(",".join(f"{k.split('.')[-1]}={v}" for k, v in p["setting"].items()), (ti, ei), fontsize=7)
    if ok:
        f = sorted((p["wall_s"], p["max_rel_error"]) for p in ok if p.get("pareto"))
        if f:
            ax.loglog(*zip(*f), "k--", lw=0.8, label="Pareto front")
    ax.axvline(result["reference"]["wall_s"], color="r", lw=0.8, label=f"reference ({result['reference']['mode']})")
    ax.set(xlabel="wall time [s]", ylabel="max relative error of the qoi", title="speed against error")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def cli(args) -> int:
    sweep = parse_sweep(args.sweep)
    base = parse_set(args.set)
    ref_set = parse_set(args.reference_set)
    sweep_points(args.case, sweep, base, args.reference_mode, ref_set, args.dem, args.mode)
    from .run import study_dir
    out = study_dir(args.out, f"bench-{Path(args.case).stem}")
    try:
        r = bench(args.case, sweep, base, args.reference_mode, ref_set, args.dem, args.mode, out, args.qoi or None)
    except CaseError:  # (a --qoi the reference does not have): no half study left behind
        import shutil
        shutil.rmtree(out, ignore_errors=True)
        raise
    print(f"reference: --mode {r['reference']['mode']} {r['reference']['set'] or ''} "
          f"({'cached' if r['reference']['cached'] else 'run'}, {r['reference']['wall_s']:.2f} s)")
    for p in r["points"]:
        err = f"{p['max_rel_error']:.2e}" if p["max_rel_error"] is not None else "n/a"
        print(f"  {p['dem'] + ' ' if ',' in args.dem else ''}{p['setting']}: {p['status']}, {p['wall_s']:.2f} s, max rel. error {err}"
              f"{'  (Pareto)' if p.get('pareto') else ''}")
    print(f"  results: {out}/speed_error.json\n  plot:    {out}/speed_error.png")
    return 0
