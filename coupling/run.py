"""``femdem run``: case -> Simulation -> clock loop -> run directory."""
from __future__ import annotations

import datetime as dt
import platform
import resource
import sys
import time
from pathlib import Path

from . import checkpoint
from .case import Case
from .output import RunOutput
from .params import CaseError
from .simulation import Instability, run_clock


def default_out(case: Case, mode: str) -> Path:
    stamp = dt.datetime.now().strftime("%Y%m%d-%H%M%S")
    return Path("runs") / f"{case.name}-{mode}-{stamp}"


def execute(case: Case, mode: str, dem: str, out: Path | None, quiet: bool,
            resume_from: Path | None = None) -> tuple[int, Path, dict]:
    """Run one case (or continue it from the checkpoint ``resume_from``); returns (exit code,
    run directory, summary)."""
    scene = case.scene
    if mode not in scene.MODES:
        raise CaseError(f"--mode {mode}: case {case.name} supports {', '.join(scene.MODES)}")
    out = Path(out) if out else default_out(case, mode)
    try:
        writer = RunOutput(out, resume=resume_from is not None)
    except FileExistsError:
        raise CaseError(f"--out {out}: directory exists and is not empty; allowed: a new or empty directory") from None
    checkpoint.write_run_info(writer.dir, {"case": case.name, "case_file": str(case.path), "mode": mode, "dem": dem,
                                           "parameters": case.parameters})
    t_start = time.perf_counter()
    sim, result, qoi, checks = None, None, {}, {}
    status, message = "ok", ""
    try:
        sim = scene.build(case.parameters, mode, dem)
        bar = _progress(sim, quiet)
        try:
            every = case.parameters["output.checkpoint_every"] or (sim.n_steps // 10 if sim.n_steps >= 5000 else 0)
            result = run_clock(sim, on_sample=bar.update if bar else None, on_frame=writer.frame,
                               run_dir=writer.dir, checkpoint_every=every, resume_from=resume_from)
        except Instability as exc:
            status, message, result = "unstable", str(exc), exc.partial
        finally:
            if bar:
                bar.close()
        if status == "ok":
            qoi, checks = scene.evaluate(case.parameters, result["history"], mode)
            t0 = time.perf_counter()
            scene.plot(case.parameters, result["history"], qoi, writer.dir / "plots")
            result["timing_s"]["io"] += time.perf_counter() - t0
    except CaseError:
        if resume_from is None:  # never delete the checkpoint a resume came for
            writer_cleanup(writer)
        raise
    except Exception as exc:  # a defect or an engine failure: say so in the run directory too
        status, message = "error", f"{type(exc).__name__}: {exc}"
    finally:
        if sim is not None:
            sim.close()
    result = result or {"history": {}, "timing_s": {}, "energy": {}, "steps": 0}
    summary = {
        "case": case.name, "case_file": str(case.path), "scene": scene.NAME, "mode": mode,
        "dem_backend": dem if mode != "fem" else None,
        "versions": {"python": platform.python_version(), **_versions(), **(sim.versions if sim else {})},
        "parameters": case.parameters, "counts": sim.counts if sim else {},
        "clock": {**(sim.clock_info if sim else {}), "steps": result["steps"],
                  "t_end": result["steps"] * sim.dt if sim else 0.0},
        "timing_s": dict(result["timing_s"], total=time.perf_counter() - t_start),
        "memory_peak_mb": _memory_peak_mb(),
        "energy": result["energy"], "qoi": qoi, "checks": checks, "status": status, "message": message,
    }
    final = writer.finish(summary, result["history"], keep_checkpoint=status != "ok")
    return {"ok": 0, "unstable": 3, "error": 1}[status], final, summary


def _memory_peak_mb() -> dict[str, float]:
    """Peak resident memory (MB) of this process (since it started: in one CLI call, the run)
    and of its finished children (engine worker processes)."""
    kb = lambda who: resource.getrusage(who).ru_maxrss / 1024.0  # Linux reports KiB
    return {"orchestrator": kb(resource.RUSAGE_SELF), "workers": kb(resource.RUSAGE_CHILDREN)}


def writer_cleanup(writer: RunOutput) -> None:
    import shutil
    shutil.rmtree(writer.dir, ignore_errors=True)


def _progress(sim, quiet: bool):
    if quiet or not sys.stderr.isatty():
        return None
    from tqdm import tqdm
    bar = tqdm(total=sim.n_steps, unit="step", dynamic_ncols=True, leave=False)
    last = [0]

    class _Bar:
        def update(self, step, t):
            bar.update(step - last[0])
            last[0] = step

        def close(self):
            bar.close()

    return _Bar()


def _versions() -> dict:
    import numpy
    import scipy
    import skfem
    return {"numpy": numpy.__version__, "scipy": scipy.__version__, "scikit-fem": skfem.__version__}


def resume(run_dir: Path, quiet: bool) -> tuple[int, Path, dict]:
    """Continue a run that was stopped (killed, or lost its machine) from its last checkpoint."""
    from .case import load_case
    run_dir = Path(run_dir)
    final = run_dir.with_name(run_dir.name[: -len(".partial")]) if run_dir.name.endswith(".partial") else run_dir
    partial = final.with_name(final.name + ".partial")
    if (final / "summary.json").exists():
        raise CaseError(f"--resume {run_dir}: this run finished; allowed: the directory of a stopped run")
    info_path = partial / "run.json"
    ck_dir = checkpoint.latest(partial) if partial.exists() else None
    if not info_path.exists() or ck_dir is None:
        raise CaseError(f"--resume {run_dir}: no checkpoint there; allowed: a run directory with checkpoint/ "
                        "(runs write one every output.checkpoint_every steps)")
    import json
    info = json.loads(info_path.read_text())
    case = load_case(info["case_file"], info["parameters"])
    return execute(case, info["mode"], info["dem"], final, quiet, resume_from=ck_dir)
