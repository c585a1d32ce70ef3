"""``femdem bench``: speed against error over a sweep of parameters, with a cached reference.

Every sweep point is a normal run (its own run directory under the bench directory); its
error is the relative difference of each quantity of interest from the reference run (by
default the same case in ``--mode dem``, the whole domain as particles, or a run with
``--reference-set`` overrides, e.g. the finest setting). A quantity never reached (nan, None)
in a run, or 0 in the reference, has no relative error: it is listed as not compared, with why;
a point with a quantity reached in one of the two runs only has no max error (n/a: no number
measures that) and is never on the Pareto front. References are cached by their resolved
parameters, mode and engine and the contents of the files they name, so sweeps reuse them (one
cached by a version that counted its plots in its wall time runs again).
Writes speed_error.json and speed_error.png (wall time against error, the Pareto front marked).

Speed is a ratio measured side by side: each point's ``speedup`` is the reference's wall time
over its own. A cached reference ran at another hour (this VM's speed moves by a third from hour
to hour); with ``--repeat N`` the bench runs the reference again in each of N rounds, each
round the reference then every point, and reports the medians: each run's wall time, and each
point's speedup as the median of its rounds' ratios (a drift of the machine between rounds
then cancels within each ratio). A run's wall time here is its ``timing_s.total`` less its
kernels' compilation (``timing_s.compile``: a first run on a new machine, or of a build no run
used before, compiles what later runs load from the cache; physics/compile_clock.py) and less
the drawing of its plots from its finished history (``timing_s.plots``: about a second in a
lone run, half of it importing matplotlib, half a second in a bench; whatever the model, so a
tenth of a 4 s coupled run's wall and a sixtieth of a 31 s all-DEM run's: docs/benchmarks.md,
session 47); each run's compile and plot seconds are kept beside its wall time.
"""
from __future__ import annotations

import hashlib
import itertools
import json
import os
import statistics
from pathlib import Path

import numpy as np

from .case import Case, input_digests, load_case
from .checks import relative_difference
from .params import CaseError, parse_set
from .output import write_json
from .run import compile_s, execute, plots_s, wall_s


def _cache_dir() -> Path:
    from . import CACHE
    return Path(os.environ.get("FEMDEM_CACHE_DIR") or CACHE) / "references"


def _key(case: Case, mode: str, dem: str) -> str:
    """The cache's name for a reference run: its parameters, mode and engine, and the contents
    of its case file and of the files its parameters name (a load curve's CSV edited in place is
    another reference)."""
    key = {"p": case.parameters, "mode": mode, "dem": dem, "files": input_digests(case.path, case.parameters)}
    blob = json.dumps(key, sort_keys=True, default=str)
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
        twice = sorted({v for v in values if values.count(v) > 1})
        if twice:
            raise CaseError(f"--sweep {item}: {', '.join(twice)} given twice; allowed: each value once")
        out[key.strip()] = values
    return out


def reference(case_name: str, overrides: dict, mode: str, dem: str, out: Path,
              fresh: bool = False) -> tuple[dict, bool]:
    """The reference summary (from the cache when the same run was made before, unless
    ``fresh``: run again, and the cache holds this run's)."""
    case = load_case(case_name, overrides)
    path = _cache_dir() / f"{_key(case, mode, dem)}.json"
    if path.exists() and not fresh:
        cached = json.loads(path.read_text())
        if "plots" in cached["timing_s"]:  # (one cached before session 47 counted its plots in its wall)
            return cached, True
    code, _, summary = execute(case, mode, dem, out, quiet=True)
    if code:
        raise CaseError(f"reference run ({mode}) did not finish: {summary['message']}")
    path.parent.mkdir(parents=True, exist_ok=True)
    write_json(path, summary)
    return summary, False


def pareto(times: np.ndarray, errors: np.ndarray) -> np.ndarray:
    """Indices of the points no other point beats in both wall time and error; times: (n,) s,
    errors: (n,). A point with a time or error not finite is never on the front (a nan compares
    false with everything, so it would never be beaten) and beats none."""
    finite = np.isfinite(times) & np.isfinite(errors)
    idx = []
    for i in np.flatnonzero(finite):
        beaten = finite & (times <= times[i]) & (errors <= errors[i]) & ((times < times[i]) | (errors < errors[i]))
        if not beaten.any():
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
    load_case(case_name, base)  # the fixed values, then each swept one, named by their options
    load_case(case_name, {**base, **ref_set}, "--reference-set")
    for key, values in sweep.items():
        for v in values:
            load_case(case_name, {**base, key: v}, "--sweep")
    keys = list(sweep)
    todo = [(ref_mode, engines[0], {**base, **ref_set})]
    todo += [(mode, e, {**base, **dict(zip(keys, combo))})
             for e, combo in itertools.product(engines, itertools.product(*(sweep[k] for k in keys)))]
    for k, (m, engine, sets) in enumerate(todo):
        case = load_case(case_name, sets)
        if m not in case.scene.MODES:
            flag = "--reference-mode" if k == 0 else "--mode"
            raise CaseError(f"{flag} {m}: case {case.name} supports {', '.join(case.scene.MODES)}")
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


def relative_errors(names: list[str], qoi: dict, ref_qoi: dict) -> tuple[dict[str, float], dict[str, str], bool]:
    """(|q - q_ref| / |q_ref| of the names both runs reached, {name: why it is not compared}
    (checks.relative_difference), whether a name was reached in one run only: the runs then
    disagree on whether it happened at all, and no relative error says by how much)."""
    errors, why = {}, {}
    for q in names:
        d = relative_difference(qoi.get(q), ref_qoi.get(q))
        (why if isinstance(d, str) else errors)[q] = d
    one_sided = any(w.startswith("not reached") for w in why.values())
    return errors, why, one_sided


def bench(case_name: str, sweep: dict[str, list[str]], base: dict, ref_mode: str, ref_set: dict, dem: str,
          mode: str, out: Path, qoi: list[str] | None = None, repeat: int = 1) -> dict:
    """Run the sweep; dem: one engine or several separated by commas (an axis of the sweep:
    one curve each; the reference runs on the first); qoi: names compared with the reference
    (default: compared_qoi); repeat: rounds of the reference and every point (module
    docstring), each run in a directory of its own (NAME-rK)."""
    sweep_points(case_name, sweep, base, ref_mode, ref_set, dem, mode)
    out.mkdir(parents=True, exist_ok=True)
    engines = dem.split(",")
    if mode != "fem" or ref_mode != "fem":  # import the engine once, so no run pays for it
        from dem_region.backends import make_backend
        make_backend("yade").finalize() if "yade" in engines else None
    keys = list(sweep)
    combos = list(itertools.product(engines, itertools.product(*(sweep[k] for k in keys))))
    refs, runs = [], [[] for _ in combos]  # each round's reference summary; each point's summaries
    for r in range(repeat):
        tag = f"-r{r + 1}" if repeat > 1 else ""
        ref, cached = reference(case_name, {**base, **ref_set}, ref_mode, engines[0], out / f"reference{tag}",
                                fresh=repeat > 1)
        refs.append(ref)
        unknown = [q for q in qoi or [] if q not in ref["qoi"]]
        if unknown:  # known only once the reference has run: refused before any sweep point runs
            raise CaseError(f"--qoi {unknown[0]}: not a quantity of this case; allowed: {', '.join(ref['qoi'])}")
        for k, (engine, combo) in enumerate(combos):
            name = "_".join(f"{key.split('.')[-1]}{v}" for key, v in zip(keys, combo)) or "base"
            name = f"{engine}_{name}" if len(engines) > 1 else name
            runs[k].append(execute(load_case(case_name, {**base, **dict(zip(keys, combo))}), mode, engine,
                                   out / f"{name}{tag}", quiet=True)[2])
    ref_walls = [wall_s(ref) for ref in refs]
    points = []
    for (engine, combo), mine in zip(combos, runs):
        s = mine[0]  # (the qoi of the first round; the others' are the same when the runs repeat)
        names = qoi or compared_qoi(load_case(case_name, {**base, **dict(zip(keys, combo))}).parameters, s["qoi"],
                                    refs[0]["qoi"])
        errors, not_compared, one_sided = relative_errors(names, s["qoi"], refs[0]["qoi"])
        walls = [wall_s(run) for run in mine]
        status = next((run["status"] for run in mine if run["status"] != "ok"), "ok")
        points.append({"setting": dict(zip(keys, combo)), "dem": engine, "status": status,
                       "wall_s": statistics.median(walls), "wall_s_runs": walls,
                       "compile_s_runs": [compile_s(run) for run in mine],
                       "plots_s_runs": [plots_s(run) for run in mine],
                       "speedup": statistics.median(w_ref / w for w_ref, w in zip(ref_walls, walls)),
                       "repeatable": all(_same_qoi(run["qoi"], s["qoi"]) for run in mine),
                       "timing_s": s["timing_s"], "qoi": s["qoi"], "rel_error": errors,
                       "not_compared": not_compared,
                       "max_rel_error": max(errors.values()) if errors and not one_sided else None})
    ok = [p for p in points if p["status"] == "ok" and p["max_rel_error"] is not None]
    front = pareto(np.array([p["wall_s"] for p in ok]), np.array([p["max_rel_error"] for p in ok])) if ok else []
    for i in front:
        ok[i]["pareto"] = True
    result = {"case": case_name, "mode": mode, "dem": dem, "repeat": repeat,
              "reference": {"mode": ref_mode, "set": ref_set, "cached": cached, "wall_s": statistics.median(ref_walls),
                            "wall_s_runs": ref_walls,
                            "compile_s_runs": [compile_s(ref) for ref in refs],
                            "plots_s_runs": [plots_s(ref) for ref in refs],
                            "qoi": refs[0]["qoi"]}, "points": points}
    write_json(out / "speed_error.json", result)
    _plot(result, out / "speed_error.png")
    return result


def _same_qoi(a: dict, b: dict) -> bool:
    """The same quantities to the bit (a quantity never reached, None or nan, in both)."""
    same = lambda x, y: x == y or (x is None and y is None) or (isinstance(x, float) and isinstance(y, float)
                                                                and np.isnan(x) and np.isnan(y))
    return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)


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
    if not 1 <= args.repeat <= 20:
        raise CaseError(f"--repeat {args.repeat}: allowed an integer from 1 to 20 (rounds of the reference and "
                        "every point)")
    sweep = parse_sweep(args.sweep)
    base = parse_set(args.set)
    ref_set = parse_set(args.reference_set)
    sweep_points(args.case, sweep, base, args.reference_mode, ref_set, args.dem, args.mode)
    from .run import study_dir
    out = study_dir(args.out, f"bench-{Path(args.case).stem}")
    try:
        r = bench(args.case, sweep, base, args.reference_mode, ref_set, args.dem, args.mode, out, args.qoi or None,
                  args.repeat)
    except CaseError:  # (a --qoi the reference does not have): no half study left behind
        import shutil
        shutil.rmtree(out, ignore_errors=True)
        raise
    ref, n = r["reference"], args.repeat
    how = f"{n} runs, median" if n > 1 else ("cached: run at another time," if ref["cached"] else "run")
    print(f"reference: --mode {ref['mode']} {ref['set'] or ''} ({how} {ref['wall_s']:.2f} s)")
    for p in r["points"]:
        err = f"{p['max_rel_error']:.2e}" if p["max_rel_error"] is not None else "n/a"
        err += _not_compared_note(p.get("not_compared", {}))
        print(f"  {p['dem'] + ' ' if ',' in args.dem else ''}{p['setting']}: {p['status']}, {p['wall_s']:.2f} s"
              f"{' (median)' if n > 1 else ''}, {p['speedup']:.2f} x the reference's speed, max rel. error {err}"
              f"{'  (Pareto)' if p.get('pareto') else ''}"
              f"{'' if p['repeatable'] else '  (its qoi differ between rounds: not repeatable)'}")
    compiled = sum(sum(p["compile_s_runs"]) for p in r["points"])
    compiled += 0.0 if ref["cached"] else sum(ref["compile_s_runs"])  # (a cached one ran at another time)
    if compiled > 0.05:
        print(f"  (kernels compiled in these runs: {compiled:.1f} s in all, left out of the wall times)")
    drawn = [s for p in r["points"] for s in p["plots_s_runs"]] + ([] if ref["cached"] else ref["plots_s_runs"])
    drawn = [s for s in drawn if s > 0.0]  # (a run that stopped drew none)
    if drawn:
        print(f"  (each run's plots, drawn after its results: median {statistics.median(drawn):.2f} s, left out of "
              "the wall times)")
    print(f"  results: {out}/speed_error.json\n  plot:    {out}/speed_error.png")
    return 0


def _not_compared_note(why: dict[str, str]) -> str:
    """" (not compared: a, b reached in neither run; c not reached in the reference)", or ""."""
    by_reason = {}
    for q, reason in why.items():
        by_reason.setdefault(reason, []).append(q)
    groups = [", ".join(qs) + " " + reason for reason, qs in by_reason.items()]
    return f" (not compared: {'; '.join(groups)})" if groups else ""
