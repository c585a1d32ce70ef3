"""``femdem compare CASE --dem a,b``: the same case on several engines, side by side.

Writes compare.json and prints a table: every quantity of interest per engine, its largest
relative difference from the first engine, the checks' verdicts and the wall time per engine
(less any compiling of kernels, a first run's cost, and the plots' drawing: coupling.run.wall_s).
A comparison stopped half way (Ctrl-C, SIGTERM, a killed machine) is finished by the same
command with the same --out: the engines' finished runs are kept, a stopped one resumed.
"""
from __future__ import annotations

import json
from pathlib import Path

from .case import ENGINES, load_case, refuse_ineffective
from .checks import relative_difference
from .params import CaseError, parse_set
from .output import as_json, write_json
from .run import compile_s, execute, resume, study_dir, wall_s


def plan(case_name: str, engines: list[str], sets: dict, mode: str | None) -> tuple:
    """(case, mode) of a comparison, every input checked before anything runs or is written."""
    bad = [e for e in engines if e not in ENGINES]
    if bad or len(engines) < 2 or len(set(engines)) < len(engines):
        raise CaseError(f"--dem {','.join(engines)}: allowed two or more different engines of {', '.join(ENGINES)}, "
                        "comma separated")
    case = load_case(case_name, sets)
    if mode is None and tuple(case.scene.MODES) == ("fem",):
        raise CaseError(f"CASE {case_name}: runs all-FEM only (no DEM engine to compare); allowed: a case with a "
                        "coupled or dem mode")
    mode = mode or case.scene.MODES[0]
    if mode == "fem":
        raise CaseError(f"--mode {mode}: an FEM-only run uses no DEM engine; allowed coupled or dem")
    if mode not in case.scene.MODES:
        raise CaseError(f"--mode {mode}: case {case.name} supports {', '.join(case.scene.MODES)}")
    refuse_ineffective(case, mode, engines[0])
    return case, mode


def compare(case_name: str, engines: list[str], sets: dict, mode: str | None, out: Path) -> dict:
    case, mode = plan(case_name, engines, sets, mode)
    runs = {}
    for engine in engines:
        try:
            runs[engine] = _finished(out / engine, case, mode, engine) or _run(case_name, case, sets, mode, engine, out)
        except BaseException as stop:
            if not isinstance(stop, Exception):  # Ctrl-C, SIGTERM: the comparison goes on from here
                stop.hint = f"the comparison is kept in {out}: finish it with the same command and --out {out}"
            raise
    first = engines[0]
    rows = []
    for q in runs[first]["qoi"]:
        values = {e: runs[e]["qoi"].get(q) for e in engines}
        rows.append({"qoi": q, "values": values, "max_rel_diff": max_rel_diff(values, first)})
    result = {"case": case.name, "mode": mode, "engines": engines, "rows": rows,
              "status": {e: runs[e]["status"] for e in engines},
              "checks_passed": {e: all(c["passed"] for c in runs[e]["checks"].values()) for e in engines},
              "wall_s": {e: wall_s(runs[e]) for e in engines},  # (without compiling kernels, a first run's, and plots)
              "compile_s": {e: compile_s(runs[e]) for e in engines},
              "dem_s": {e: runs[e]["timing_s"].get("dem", 0.0) for e in engines}}
    write_json(out / "compare.json", result)
    return result


def _run(case_name: str, case, sets: dict, mode: str, engine: str, out: Path) -> dict:
    """One engine's run (its summary): resumed where a stopped comparison of the same case left
    it, else anew."""
    partial = out / f"{engine}.partial"
    if partial.is_dir():
        _same_run(json.loads((partial / "run.json").read_text()), case, mode, engine, out)
        return resume(partial, quiet=True)[2]
    return execute(load_case(case_name, sets), mode, engine, out / engine, quiet=True)[2]


def _finished(run_dir: Path, case, mode: str, engine: str) -> dict | None:
    """The summary of this engine's finished run of the same case, mode and parameters in run_dir
    (None: not run yet); CaseError for a run of another case there."""
    path = run_dir / "summary.json"
    if not path.is_file():
        return None
    s = json.loads(path.read_text())
    _same_run({**s, "dem": s.get("dem_backend")}, case, mode, engine, run_dir.parent)
    return s


def _same_run(info: dict, case, mode: str, engine: str, out: Path) -> None:
    """CaseError unless ``info`` (a run's run.json or summary.json) is this comparison's run on
    ``engine``: the same case, mode and parameters (a stopped run of other --set values would be
    finished and compared as this one's)."""
    if (info.get("case"), info.get("mode"), info.get("dem"), info.get("parameters")) != \
            (case.name, mode, engine, as_json(dict(case.parameters))):
        raise CaseError(f"--out {out}: holds a run on {engine} of another case or other parameters; "
                        "allowed: the same comparison's directory, or a new or empty one")


def continues(engines: list[str]):
    """Whether a directory holds a comparison of these engines stopped half way: only their runs'
    directories (finished or .partial), no compare.json."""
    names = {e for e in engines} | {f"{e}.partial" for e in engines}
    return lambda d: all(p.name in names for p in d.iterdir())


def max_rel_diff(values: dict, first: str) -> float | None:
    """The largest |v - v_first| / |v_first| over the engines' values {engine: value}; None where
    no such number says it (checks.relative_difference: a value not reached, or v_first = 0
    beside another value). It read 0 whenever the first engine's value was 0, and nan into the
    JSON."""
    d = [relative_difference(v, values[first]) for v in values.values()]
    return None if any(isinstance(x, str) for x in d) else max(d)


def cli(args) -> int:
    engines, sets = [e.strip() for e in args.dem.split(",")], parse_set(args.set)
    plan(args.case, engines, sets, args.mode)
    out = study_dir(args.out, f"compare-{Path(args.case).stem}", continues(engines))
    r = compare(args.case, engines, sets, args.mode, out)
    width = max(len(row["qoi"]) for row in r["rows"]) if r["rows"] else 4
    print(f"{r['case']} ({r['mode']}):")
    print(f"  {'qoi':{width}s}  " + "  ".join(f"{e:>14s}" for e in r["engines"]) + "  max rel. diff")
    for row in r["rows"]:
        vals = "  ".join(f"{row['values'][e]:14.6g}" if row["values"][e] is not None else f"{'n/a':>14s}"
                         for e in r["engines"])
        diff = f"{row['max_rel_diff']:.2e}" if row["max_rel_diff"] is not None else "n/a"
        print(f"  {row['qoi']:{width}s}  {vals}  {diff}")
    print(f"  {'status':{width}s}  " + "  ".join(f"{r['status'][e]:>14s}" for e in r["engines"]))
    print(f"  {'checks passed':{width}s}  " + "  ".join(f"{str(r['checks_passed'][e]):>14s}" for e in r["engines"]))
    print(f"  {'wall time [s]':{width}s}  " + "  ".join(f"{r['wall_s'][e]:14.3f}" for e in r["engines"]))
    print(f"  results: {out}/compare.json")
    status = set(r["status"].values())
    return 1 if "error" in status else 3 if "unstable" in status else 0
