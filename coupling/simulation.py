"""The shared explicit clock: an ordered list of named stages run by a trivial timed loop.

A scene assembles a :class:`Simulation` from its participants; one clock step calls every
stage once in order, so per-stage timing comes for free and the ordering is visible in one
place. A FEM run: fem.kick_drift, fem.forces, fem.kick. A coupled run: the engine's step,
m times per FEM step, each running inside its hook laws, interface.read, fem.forces (the
FEM's own forces every m-th), fem.kick_drift, interface.write (participants/clock.py).
summary.json "stages" lists them in this order with their wall times. Instability guards
run at every history sample.
"""
from __future__ import annotations

import math
import time
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from .params import CaseError

# models: bond laws and impactors the coupling layer evaluates on the engine's particles
TIMERS = ("fem", "dem", "interface", "models", "transport", "io", "orchestrator")


class Instability(RuntimeError):
    """The run diverged: message names the region, step and likely cause (exit code 3)."""


@dataclass
class Stage:
    """One named phase of a clock step; ``timer``: its summary.json timing bucket;
    ``substages``: the stages its participant runs inside it, in order (an engine's hook runs
    them between its force evaluation and its move); ``seconds``: wall time so far (its
    substages' included); ``repeat(n)``: n clock steps of this stage in one call, where the
    stage is the whole clock step (an engine in a worker then crosses the process boundary
    once per call, not once per step)."""

    name: str
    timer: str
    run: Callable[[], None]
    substages: list["Stage"] = field(default_factory=list)
    seconds: float = 0.0
    repeat: Callable[[int], None] | None = None


def run_stages(stages: list[Stage], steps: int = 1) -> None:
    """Run ``stages`` in order, each timed, ``steps`` clock steps over (a lone stage that can
    repeat itself in one call)."""
    clock = time.perf_counter
    if steps > 1 and len(stages) == 1 and stages[0].repeat is not None:
        t0 = clock()
        stages[0].repeat(steps)
        stages[0].seconds += clock() - t0
        return
    for _ in range(steps):
        for stage in stages:
            t0 = clock()
            stage.run()
            stage.seconds += clock() - t0


def stage_timing(stages: list[Stage], within: str = "") -> list[dict]:
    """[{name, timer, s, within}] of ``stages`` and their substages in running order; a
    stage's ``s`` excludes its substages (the engine's own time, for an engine step)."""
    rows = []
    for st in stages:
        own = st.seconds - sum(sub.seconds for sub in st.substages)
        rows.append({"name": st.name, "timer": st.timer, "s": own, **({"within": within} if within else {})})
        rows += stage_timing(st.substages, st.name)
    return rows


@dataclass
class FieldFrame:
    """Mesh and data for one XDMF frame: points (n, 3) m, cells {type: (m, k)}, nodal data,
    and cell data {name: [array per cell block, in the order of ``cells``]}."""

    points: np.ndarray
    cells: dict[str, np.ndarray]
    point_data: dict[str, np.ndarray]
    cell_data: dict[str, list[np.ndarray]] | None = None


@dataclass
class Simulation:
    """Everything the clock loop needs from a scene.

    dt: s; n_steps: clock steps; history_every: steps between history samples;
    probes: name -> callable giving a float (SI) at a sample; energies: callable giving the
    ledger {kinetic, internal, external_work, dissipated} in J; fields: optional callable for
    XDMF frames (``field_frames`` of them, evenly spaced); counts / clock_info: echoed in
    summary.json; close: releases engines.
    """

    stages: list[Stage]
    dt: float
    n_steps: int
    history_every: int
    probes: dict[str, Callable[[], float]]
    energies: Callable[[], dict[str, float]]
    counts: dict[str, int] = field(default_factory=dict)
    clock_info: dict[str, float] = field(default_factory=dict)
    fields: Callable[[], FieldFrame] | None = None
    field_frames: int = 0
    energy_growth_tol: float = 0.05
    close: Callable[[], None] = lambda: None
    timing_correction: Callable[[], dict[str, float]] | None = None
    instability_hint: str = "time step above the stable limit, or a penalty too stiff"
    # extra run-time checks at each sample: each returns None or a diagnostic (region, cause)
    guards: list[Callable[[], str | None]] = field(default_factory=list)
    # checkpoint support: () -> (state dict, engine_save(directory) or None); (state, checkpoint directory) -> None
    checkpoint: Callable[[], tuple[dict, Callable | None]] | None = None
    restore: Callable[[dict, object], None] | None = None
    versions: dict[str, str] = field(default_factory=dict)
    # name -> (time s, capture() -> {field: array}): arrays taken at the first sample at or
    # after that time (damage pictures), returned in the history as "<name>.<field>"
    snapshots: dict[str, tuple[float, Callable[[], dict[str, np.ndarray]]]] = field(default_factory=dict)
    # brings the orchestrator's copies of models that run elsewhere (an engine's worker) up to
    # date before anything reads them: samples, frames, checkpoints, the end of the run
    sync: Callable[[], None] | None = None
    # what the scene could model only with a compromise, or not as well as its checks assume:
    # one line each, printed before the run and kept in summary.json
    warnings: list[str] = field(default_factory=list)
    # a zone that grows during the run (coupling/study/growth.py): called after each sample, at
    # each check (every growth.every steps) and at the step a check asked to convert at
    # (growth.pending); returns the Simulation the run continues with (its state carried over)
    # or None; its state() goes into checkpoints, and rebuild(state) makes the Simulation a
    # resume restores
    growth: object = None


# The qoi are read off the history: a peak is its largest sample, a duration counts samples,
# an arrival time is a centroid. Below this many samples after t = 0 a peak falls between
# them (0 N for a whole impact) and a centroid divides by zero, so a sparser history is refused.
MIN_HISTORY_SAMPLES = 10


def refuse_sparse_history(p: dict, sim: Simulation) -> None:
    """CaseError (exit 2) for an output.history_every the run ``sim`` of ``p`` cannot use: one
    that leaves it fewer than MIN_HISTORY_SAMPLES samples after t = 0, or one its scene
    overrides with its own sampling (a setting with no effect). Called on the built model, before
    it runs (run.execute: the step count is first known there)."""
    every = p.get("output.history_every", 0)
    if not every:  # 0: the scene's own sampling
        return
    n = sim.n_steps
    samples = -(-n // every)  # ceil: the last step is always sampled
    problem = None
    if sim.history_every != every:
        problem = (f"has no effect, this case samples its history every {sim.history_every} clock step(s) "
                   "whatever it is set to; allowed: 0 (the case's own sampling)")
    elif every > 1 and samples < min(MIN_HISTORY_SAMPLES, n):
        most = max(1, (n - 1) // (MIN_HISTORY_SAMPLES - 1))  # the largest interval still giving that many
        problem = (f"leaves this run of {n} clock steps {samples} history sample(s) after t = 0, fewer than "
                   f"{MIN_HISTORY_SAMPLES} (its peaks and times are read from the history); allowed: 0 (about "
                   f"1000 samples) or 1 to {most}")
    if problem:
        raise CaseError(f"output.history_every = {every}: {problem}")


def energy_scale(e: dict[str, float]) -> float:
    """Size of an energy ledger (J): the largest of stored, worked and dissipated energy."""
    return max(abs(e["kinetic"]) + abs(e["internal"]), abs(e["external_work"]), abs(e["dissipated"]))


def energy_balance_error(e: dict[str, float], e0: dict[str, float], scale: float) -> float:
    """|(K + U + D - W) - (K0 + U0)| relative to ``scale`` (the largest ledger seen so far)."""
    total = e["kinetic"] + e["internal"] + e["dissipated"] - e["external_work"]
    total0 = e0["kinetic"] + e0["internal"]
    return abs(total - total0) / max(scale, 1e-300)


def run_clock(sim: Simulation, on_sample: Callable[[int, float], None] | None = None,
              on_frame: Callable[[float, FieldFrame], None] | None = None, run_dir=None,
              checkpoint_every: int = 0, resume_from=None) -> dict:
    """Advance ``sim`` by its n_steps; returns {history, timing_s, energy, steps}.

    With run_dir and checkpoint_every > 0 a checkpoint is written every that many steps;
    resume_from (a checkpoint directory) continues such a run where it stopped.
    Raises Instability (with the samples gathered so far attached as ``.partial``) when a
    probe or energy is not finite or the energy balance error exceeds sim.energy_growth_tol.
    """
    from . import checkpoint as ck

    timing = dict.fromkeys(TIMERS, 0.0)
    retired: list[dict] = []  # the stage rows of the models a growing zone replaced
    names = ["time", *sim.probes, "kinetic", "internal", "external_work", "dissipated", "balance_error_rel"]
    hist: dict[str, list[float]] = {k: [] for k in names}
    taken: dict[str, np.ndarray] = {}
    if sim.sync is not None:
        sim.sync()
    e0 = sim.energies()
    first = 1
    if resume_from is not None:
        saved = ck.read(resume_from)
        try:
            if sim.growth is not None and "growth" in saved["loop"]:  # the zone as it had grown by then
                sim = sim.growth.rebuild(saved["loop"]["growth"], sim)
            sim.restore(saved["simulation"], Path(resume_from))  # the engine's files are in the same directory
        except (OSError, EOFError, KeyError, ValueError, zipfile.BadZipFile) as exc:  # (a damaged or edited run)
            from dem_region.backends.base import EngineUnavailable
            if isinstance(exc, EngineUnavailable):  # (an engine that cannot start: not the checkpoint's)
                raise
            raise ck.Unusable(resume_from, exc) from None
        loop = saved["loop"]
        samples = len(np.asarray(loop["history"]["time"]))  # (a series the checkpoint's code did not record: nan)
        hist = {k: list(np.asarray(loop["history"][k]).tolist()) if k in loop["history"] else [math.nan] * samples
                for k in names}
        e0 = {k: float(v) for k, v in loop["e0"].items()}
        taken = {k: np.asarray(v) for k, v in loop.get("snapshots", {}).items()}
        first = int(loop["step"]) + 1
    frame_every = max(1, sim.n_steps // sim.field_frames) if sim.fields and sim.field_frames else 0
    clock = time.perf_counter

    scale = [energy_scale(e0) if resume_from is None else float(saved["loop"]["scale"])]

    def sync() -> None:
        if sim.sync is not None:
            t0 = clock()
            sim.sync()
            timing["transport"] += clock() - t0

    def sample(step: int) -> None:
        sync()
        t0 = clock()
        e = sim.energies()
        scale[0] = max(scale[0], energy_scale(e))
        values = {"time": step * sim.dt, **{k: float(p()) for k, p in sim.probes.items()}, **e,
                  "balance_error_rel": energy_balance_error(e, e0, scale[0])}
        for k in names:
            hist[k].append(values[k])
        for name, (t_snap, capture) in sim.snapshots.items():
            if values["time"] >= t_snap * (1 - 1e-9) and not any(k.startswith(name + ".") for k in taken):
                taken.update({f"{name}.{k}": np.asarray(v) for k, v in capture().items()})
        timing["orchestrator"] += clock() - t0
        bad = [k for k, v in values.items() if not math.isfinite(v)]
        if bad:
            raise Instability(f"step {step}, t = {values['time']:.4g} s: {bad[0]} is not finite; "
                              f"likely cause: {sim.instability_hint}")
        # the trapezoidal ledger is O(dt)-rough over the first few steps of a transient
        warm = step >= max(50, sim.n_steps // 100)
        if warm and values["balance_error_rel"] > sim.energy_growth_tol:
            raise Instability(f"step {step}, t = {values['time']:.4g} s: energy balance error "
                              f"{values['balance_error_rel']:.3g} exceeds guards.energy_growth = {sim.energy_growth_tol:g} "
                              f"(energy created); likely cause: {sim.instability_hint}")
        for guard in sim.guards:
            problem = guard()
            if problem:
                raise Instability(f"step {step}, t = {values['time']:.4g} s: {problem}")
        if on_sample:
            on_sample(step, values["time"])

    def frame(step: int) -> None:
        sync()
        t0 = clock()
        on_frame(step * sim.dt, sim.fields())
        timing["io"] += clock() - t0

    def save(step: int) -> None:
        sync()
        t0 = clock()
        state, engine_save = sim.checkpoint()
        loop = {"step": step, "e0": e0, "scale": scale[0], "history": {k: np.asarray(v) for k, v in hist.items()},
                "snapshots": dict(taken), **({"growth": sim.growth.state()} if sim.growth is not None else {})}
        ck.write(run_dir, {"simulation": state, "loop": loop}, engine_save)
        timing["io"] += clock() - t0

    can_save = run_dir is not None and checkpoint_every > 0 and sim.checkpoint is not None
    grow_every = sim.growth.every if sim.growth is not None else 0  # checks between samples (zone.grow_every)
    step = first - 1
    try:
        if resume_from is None:
            sample(0)
        if frame_every and on_frame and resume_from is None:  # a resume keeps the frames before its checkpoint
            frame(step)
        while step < sim.n_steps:
            # the steps up to the next thing the loop does in one go (a sample, a frame, a checkpoint)
            nxt = min(sim.n_steps, _next_multiple(step, sim.history_every),
                      _next_multiple(step, frame_every) if frame_every and on_frame else sim.n_steps,
                      _next_multiple(step, checkpoint_every) if can_save else sim.n_steps,
                      _next_multiple(step, grow_every) if grow_every else sim.n_steps,
                      # (a check between samples that asked to convert: at the next step, the clock's whole snapshot)
                      sim.growth.pending if sim.growth is not None and sim.growth.pending > step else sim.n_steps)
            run_stages(sim.stages, nxt - step)
            step = nxt
            sampled = step % sim.history_every == 0 or step == sim.n_steps
            if sampled:
                sample(step)
            if sim.growth is not None and step < sim.n_steps and (
                    sampled or (grow_every and step % grow_every == 0) or step == sim.growth.pending):
                if not sampled:
                    sync()  # (the growth reads the participants' snapshots)
                t0 = clock()
                grown = sim.growth(step)
                if grown is not None:  # the run goes on with the grown zone's model
                    timing.update(_corrected(timing, sim))
                    retired += stage_timing(sim.stages)
                    sim = grown
                timing["orchestrator"] += clock() - t0
            if frame_every and on_frame and step % frame_every == 0:
                frame(step)
            if can_save and step % checkpoint_every == 0 and step < sim.n_steps:
                save(step)
    except Instability as exc:
        sync()
        exc.partial = _result(hist, _corrected(timing, sim), sim.energies(), step, taken, sim, retired)  # type: ignore[attr-defined]
        raise
    sync()
    return _result(hist, _corrected(timing, sim), sim.energies(), sim.n_steps, taken, sim, retired)


def _next_multiple(step: int, every: int) -> int:
    """The first multiple of ``every`` after ``step``."""
    return (step // every + 1) * every


def _corrected(timing: dict, sim: Simulation) -> dict:
    """The timing buckets: each stage's own time in its timer's bucket, then the participants'
    corrections (a worker's transport, measured inside the engine's step)."""
    timing = dict(timing)
    for row in stage_timing(sim.stages):
        timing[row["timer"]] += row["s"]
    if sim.timing_correction:
        for k, v in sim.timing_correction().items():
            timing[k] = timing.get(k, 0.0) + v  # (and "compile": a worker's, apart from the buckets)
    return timing


def _result(hist, timing, energy, steps, snapshots, sim, retired=()) -> dict:
    """The run's result; ``simulation``: the one it ended with (a grown zone's: its counts)."""
    history = {k: np.asarray(v) for k, v in hist.items()}
    history.update(snapshots or {})
    err = history["balance_error_rel"]
    energy = dict(energy, balance_error_rel=float(err[-1]) if err.size else 0.0)
    rows = stage_timing(sim.stages)
    for old in retired:  # the same stages in the models a growing zone replaced
        row = next((r for r in rows if r["name"] == old["name"] and r.get("within") == old.get("within")), None)
        if row is not None:
            row["s"] += old["s"]
    return {"history": history, "timing_s": timing, "energy": energy, "steps": steps, "stages": rows,
            "simulation": sim}
