"""``femdem run``: case -> Simulation -> clock loop -> run directory."""
from __future__ import annotations

import datetime as dt
import errno
import os
import platform
import resource
import sys
import time
from pathlib import Path

from . import checkpoint
from .case import Case, input_digests
from .output import SCRATCH, RunInProgress, RunOutput
from .params import CaseError
from .simulation import Instability, refuse_sparse_history, run_clock


class OutOfSpace(Exception):
    """The run's device filled up (or its quota): the run stopped, its directory kept as written."""

    def __init__(self, run_dir: Path, exc: OSError, started: bool = True):
        what = (f"the run stopped and is kept there as written: free space, then --resume {run_dir}" if started
                else "nothing was run")
        super().__init__(f"no space left on the device of {run_dir} ({os.strerror(exc.errno)}); {what}")


def _full(exc: BaseException) -> bool:
    return isinstance(exc, OSError) and exc.errno in (errno.ENOSPC, errno.EDQUOT)


def default_out(case: Case, mode: str, dem: str) -> Path:
    """runs/<case>-<mode>[-<engine>]-<time>; RunOutput adds -2, -3, ... on a clash."""
    stamp = dt.datetime.now().strftime("%Y%m%d-%H%M%S")
    return Path("runs") / "-".join([case.name, mode, *([dem] if mode != "fem" else []), stamp])


def compile_s(summary: dict) -> float:
    """s, a run's kernel compilation (timing_s.compile: the cost of a first run on a machine, not
    of the model; a summary of an older version has none: 0)."""
    return summary["timing_s"].get("compile", 0.0)


def plots_s(summary: dict) -> float:
    """s, drawing a run's plots from its finished history (timing_s.plots, within io: the same
    second or so for any model, matplotlib's import half of it; an older summary has none: 0)."""
    return summary["timing_s"].get("plots", 0.0)


def wall_s(summary: dict) -> float:
    """s, a run's wall time without its kernels' compilation and its plots' drawing (neither is
    the model's computation): what bench and compare put side by side."""
    return summary["timing_s"]["total"] - compile_s(summary) - plots_s(summary)


def execute(case: Case, mode: str, dem: str, out: Path | None, quiet: bool,
            resume_from: Path | None = None, restart: bool = False) -> tuple[int, Path, dict]:
    """Run one case (or continue it from the checkpoint ``resume_from``, or with ``restart``
    run a stopped run again from the start in its own directory); returns (exit code, run
    directory, summary)."""
    scene = case.scene
    if mode not in scene.MODES:
        raise CaseError(f"--mode {mode}: case {case.name} supports {', '.join(scene.MODES)}")
    writer = open_output(out or default_out(case, mode, dem), resume_from is not None or restart, unique=not out,
                         restart=restart)
    try:
        checkpoint.write_run_info(writer.dir, {"case": case.name, "case_file": str(case.path), "mode": mode,
                                               "dem": dem, "parameters": case.parameters,
                                               "inputs": input_digests(case.path, case.parameters)})
    except OSError as exc:
        if not _full(exc):
            raise
        if resume_from is None and not restart:
            writer_cleanup(writer)
        raise OutOfSpace(writer.final, exc, started=False) from None
    from physics.compile_clock import announce_once, compile_seconds  # (numba: imported where a run starts)
    t_start, compiled_before = time.perf_counter(), compile_seconds()
    if not quiet and sys.stderr.isatty():  # (the progress bar's terminal: the compiling comes before it)
        announce_once(lambda: print("femdem: compiling the kernels for this machine (once per version of the code: "
                                    "up to a minute or so)", file=sys.stderr, flush=True))
    os.environ["FEMDEM_SCRATCH_DIR"] = str(writer.dir / SCRATCH)  # engines' files stay in the run
    sim, result, qoi, checks, printed = None, None, {}, {}, 0
    status, message = "ok", ""
    try:
        sim = scene.build(case.parameters, mode, dem)
        refuse_sparse_history(case.parameters, sim)  # (the step count is known from here)
        for line in sim.warnings:
            print(f"femdem: warning: {line}", file=sys.stderr)
        printed = len(sim.warnings)  # (the run's own warnings are printed at its end)
        if case.parameters["output.checkpoint_every"] and sim.checkpoint is None:
            raise CaseError(f"output.checkpoint_every = {case.parameters['output.checkpoint_every']}: this run cannot "
                            f"checkpoint ({_why_no_checkpoint(sim, dem)}); allowed: 0 (a killed run then resumes "
                            "from its start)")
        if resume_from is not None:
            writer.keep_frames_until(checkpoint.step_of(resume_from) * sim.dt)
        limit = case.parameters["clock.max_steps"]
        if sim.n_steps > limit:
            raise CaseError(f"clock.max_steps = {limit}: this run needs {sim.n_steps:.3g} clock steps "
                            f"({sim.n_steps * sim.dt:.4g} s at dt = {sim.dt:.4g} s); allowed: raise clock.max_steps, "
                            "or shorten clock.t_end")
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
        sim = result.pop("simulation", sim)  # a grown zone's model, if the zone grew
        if status == "ok":
            qoi, checks = scene.evaluate(case.parameters, result["history"], mode)
            if hasattr(scene, "run_warnings"):
                sim.warnings += [w for w in scene.run_warnings(case.parameters, result["history"], qoi, mode)
                                 if w not in sim.warnings]
            if sim.growth is not None and "zone_conversions" not in qoi:  # a specimen's growing window
                qoi.update(sim.growth.qoi())
                result["history"].update(sim.growth.history())
            t0 = time.perf_counter()
            scene.plot(case.parameters, result["history"], qoi, writer.dir / "plots")
            result["timing_s"]["plots"] = time.perf_counter() - t0  # (apart, as compile: see wall_s)
            result["timing_s"]["io"] += result["timing_s"]["plots"]
    except MemoryError as exc:  # a model this machine cannot hold is bad input (the meshes' and
        # lattices' own estimates say so before building; numpy's says how much it wanted)
        if resume_from is None:
            writer_cleanup(writer)
        if type(exc).__name__ == "TooLarge":
            raise CaseError(str(exc)) from None
        raise CaseError(f"the model does not fit in memory ({exc}); allowed: a coarser particle spacing or "
                        "mesh, or a smaller zone") from None
    except CaseError:
        if resume_from is None:  # never delete the checkpoint a resume came for
            writer_cleanup(writer)
        raise
    except checkpoint.Unusable as exc:
        raise CaseError(f"--resume {writer.dir}: {exc}; allowed: a checkpoint as its run wrote it (or the case run "
                        "again from its start)") from None
    except Exception as exc:  # a defect or an engine failure: say so in the run directory too
        if _full(exc):  # not the run's failure: nothing more is written, and it can go on later
            raise OutOfSpace(writer.dir, exc) from None
        import traceback
        (writer.dir / "error.log").write_text(traceback.format_exc())
        status, message = "error", f"{type(exc).__name__}: {exc} (traceback in {writer.final / 'error.log'})"
    except BaseException as exc:  # Ctrl-C, SIGTERM: the run stays in its directory (the command line names it)
        exc.run_dir = writer.dir
        raise
    finally:
        announce_once(None)
        if sim is not None:
            sim.close()
            for line in sim.warnings[printed:]:  # (a growing zone's, the far field's left-out damage)
                print(f"femdem: warning: {line}", file=sys.stderr)
        os.environ.pop("FEMDEM_SCRATCH_DIR", None)
    result = result or {"history": {}, "timing_s": {}, "energy": {}, "steps": 0}
    summary = {
        "case": case.name, "case_file": str(case.path), "scene": scene.NAME, "mode": mode,
        "dem_backend": dem if mode != "fem" else None,
        "versions": {"python": platform.python_version(), **_versions(), **(sim.versions if sim else {})},
        "parameters": case.parameters, "counts": sim.counts if sim else {},
        "clock": {**(sim.clock_info if sim else {}), "steps": result["steps"],
                  "t_end": result["steps"] * sim.dt if sim else 0.0},
        "timing_s": dict(result["timing_s"], total=time.perf_counter() - t_start,
                         compile=result["timing_s"].get("compile", 0.0) + compile_seconds() - compiled_before),
        "stages": result.get("stages", []),
        "memory_peak_mb": _memory_peak_mb(),
        "energy": result["energy"], "qoi": qoi, "checks": checks, "status": status, "message": message,
        "warnings": sim.warnings if sim else [],
    }
    try:
        final = writer.finish(summary, result["history"], keep_checkpoint=status != "ok")
    except OSError as exc:
        if _full(exc):
            raise OutOfSpace(writer.dir, exc) from None
        raise
    return {"ok": 0, "unstable": 3, "error": 1}[status], final, summary


def _why_no_checkpoint(sim, dem: str) -> str:
    if sim.stages and sim.stages[0].name == "virtual test":
        return "a virtual test runs as one stage"
    return f"--dem {dem} saves no Hertz contact history"


def open_output(out: Path, resume: bool, unique: bool, restart: bool = False) -> RunOutput:
    """The run's writer, or a one-line CaseError for a --out (--resume) that cannot hold a run."""
    out = Path(out)
    opt = "--resume" if resume else "--out"
    try:
        return RunOutput(out, resume=resume, unique=unique, restart=restart)
    except RunInProgress as exc:
        raise CaseError(f"{opt} {out}: {exc} belongs to a run that is still going (its process holds "
                        "run.lock); allowed: wait for it, or another directory") from None
    except FileExistsError as exc:
        if str(exc).endswith(".partial"):
            raise CaseError(f"{opt} {out}: {exc} exists (a run in progress, or stopped: continue it with "
                            f"--resume {exc}); allowed: a new or empty directory") from None
        what = "is a file" if out.exists() and not out.is_dir() else "is not an empty directory"
        raise CaseError(f"{opt} {out}: exists and {what}; allowed: a new or empty directory") from None
    except NotADirectoryError:
        raise CaseError(f"{opt} {out}: a parent of it is a file; allowed: a directory path") from None
    except PermissionError:
        raise CaseError(f"{opt} {out}: not writable by this user; allowed: a directory you can write") from None
    except OSError as exc:
        raise CaseError(f"{opt} {out}: cannot be created ({exc.strerror}); allowed: a writable directory path") from None


def study_dir(out: str | None, name: str, continues=lambda d: False) -> Path:
    """The directory of a bench or compare study: --out (new or empty, or one ``continues(dir)``
    says holds this study stopped half way), or runs/<name>-<time> made unique; created here,
    atomically, so two studies never share one."""
    if out == "":
        raise CaseError("--out '': empty; allowed: a directory path")
    if out:
        out = Path(out).absolute()
        if out.exists() and not out.is_dir():
            raise CaseError(f"--out {out}: exists and is a file; allowed: a new or empty directory")
        if out.exists() and any(out.iterdir()) and not continues(out):
            raise CaseError(f"--out {out}: exists and is not an empty directory; allowed: a new or empty directory")
        try:
            out.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise CaseError(f"--out {out}: cannot be created ({exc.strerror}); allowed: a writable directory path") from None
        return out
    base = Path("runs").absolute() / f"{name}-{dt.datetime.now():%Y%m%d-%H%M%S}"
    for n in range(1, 10_000):
        d = base if n == 1 else base.with_name(f"{base.name}-{n}")
        try:
            d.parent.mkdir(parents=True, exist_ok=True)
            d.mkdir()
            return d
        except FileExistsError:
            continue
        except OSError as exc:
            raise CaseError(f"--out {d}: cannot be created ({exc.strerror}); allowed: a writable working "
                            "directory, or --out DIR") from None
    raise CaseError(f"--out {base}: no free name; allowed: --out DIR")


def _memory_peak_mb() -> dict[str, float]:
    """Peak resident memory (MB) of this process (since it started: in one CLI call, the run)
    and of its finished children (engine worker processes)."""
    kb = lambda who: resource.getrusage(who).ru_maxrss / 1024.0  # Linux reports KiB
    return {"orchestrator": kb(resource.RUSAGE_SELF), "workers": kb(resource.RUSAGE_CHILDREN)}


def writer_cleanup(writer: RunOutput) -> None:
    writer.discard()


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
    """Continue a run that was stopped (killed, its engine worker killed, or its machine lost)
    from its last checkpoint."""
    from .case import load_case
    run_dir = Path(run_dir).absolute()
    final = run_dir.with_name(run_dir.name[: -len(".partial")]) if run_dir.name.endswith(".partial") else run_dir
    partial = final.with_name(final.name + ".partial")
    where = f"--resume {run_dir}"
    if (final / "summary.json").exists() and not partial.exists():
        status = _read_json(final / "summary.json", where).get("status")
        if status != "error" or checkpoint.latest(final) is None:
            raise CaseError(f"{where}: this run finished ({status}); allowed: the directory of a stopped run "
                            "(killed, or ended with an error and kept its checkpoint)")
        if (final / "run.json").is_file():  # (before anything moves)
            _same_inputs(_read_json(final / "run.json", where), where)
        # ended with an error (e.g. its engine worker was killed): back to .partial, continue
        try:
            os.replace(final, partial)
        except PermissionError:
            raise CaseError(f"{where}: not writable by this user (the run continues in {partial.name}); "
                            "allowed: a run directory you can write") from None
        os.replace(partial / "summary.json", partial / "summary.failed.json")
    info_path = partial / "run.json"
    ck_dir = checkpoint.latest(partial) if partial.is_dir() else None
    if ck_dir is None and partial.is_dir() and checkpoint.corrupt(partial):
        raise CaseError(f"{where}: the checkpoint {checkpoint.corrupt(partial)} is corrupt (cannot be read); "
                        "allowed: a run directory with a complete checkpoint")
    if not info_path.is_file():
        raise CaseError(f"{where}: no run.json there; allowed: the directory of a stopped run")
    info = _read_json(info_path, where)
    need = {"case_file": str, "mode": str, "dem": str, "parameters": dict}
    bad = [k for k, t in need.items() if not isinstance(info, dict) or not isinstance(info.get(k), t)]
    if bad:
        raise CaseError(f"{where}: run.json is corrupt ({bad[0]} missing or of the wrong type); "
                        "allowed: the run.json the run wrote")
    _same_inputs(info, where)
    case = load_case(info["case_file"], info["parameters"])
    # stopped before its first checkpoint (or a procedure that has none): run it again from
    # the start, in its own directory; the result is the uninterrupted run's
    return execute(case, info["mode"], info["dem"], final, quiet, resume_from=ck_dir, restart=ck_dir is None)


def _same_inputs(info: dict, where: str) -> None:
    """CaseError unless the run's input files (its case file, a mesh, a load curve) are as they
    were when the run started: run.json keeps its parameters, not its tables (probes, checks, its
    duration) nor the files' contents, so an edited file resumed as a mix of the two (a probe
    added: a history of nan from the checkpoint on, status ok). A run begun before the digests
    were kept is taken as it is."""
    want = info.get("inputs") if isinstance(info, dict) else None
    if not isinstance(want, dict):
        return
    now = input_digests(info["case_file"], info["parameters"])
    for key, digest in want.items():
        path = info["case_file"] if key == "case_file" else info["parameters"].get(key)
        if now.get(key) == "unreadable":
            raise CaseError(f"{where}: its input {path} ({key}) is gone or unreadable; allowed: the file as it was "
                            "when the run started, at that path")
        if now.get(key) != digest:
            raise CaseError(f"{where}: its input {path} ({key}) changed since the run started; allowed: the file as "
                            f"it was, or the edited case run anew (femdem run {info['case_file']})")


def _read_json(path: Path, where: str):
    import json
    try:
        return json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise CaseError(f"{where}: {path.name} is corrupt or unreadable ({type(exc).__name__}); "
                        "allowed: the file the run wrote") from None
