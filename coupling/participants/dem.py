"""The DEM participant: an engine (in-process or in a worker) with the coupling layer's models
on its particles (law bonds, impactors, loads), read and written in one bulk call per step;
its guards; and a run of it alone (``--mode dem``), the reference for a coupled model: the
same scene entirely as particles, with prescribed particles instead of a FEM."""
from __future__ import annotations

from typing import Callable

import numpy as np

from dem_region.backends import EngineUnavailable, make_backend
from dem_region.model_step import ModelStep, hosted_by
from dem_region.scene import DemScene, gershgorin_dt

from ..params import CaseError
from ..simulation import FieldFrame, Simulation, Stage, run_stages
from ..timestep import n_steps, time_step


class PrescribedParticles:
    """Particles ``ids`` driven with velocity(t) -> (3,) or (len(ids), 3) m/s; tracks the work
    the drive does."""

    def __init__(self, backend, ids: np.ndarray, velocity: Callable[[float], np.ndarray], dt: float,
                 dofs: str = "xyz"):
        self.backend, self.ids, self.velocity, self.dt = backend, np.asarray(ids, int), velocity, dt
        self.k = 0
        self.work = 0.0  # J, by the drive: minus the chain's force on the driven particles
        self.dofs = [("xyz".index(c)) for c in dofs]
        backend.prescribe(self.ids) if dofs == "xyz" else backend.prescribe(self.ids, dofs)
        # each step's arrays, written in place: the forces on the driven particles, their
        # velocities, the power's terms (undriven components zeroed: no work is done along them)
        self._F, self._v, self._Fv = (np.zeros((len(self.ids), 3)) for _ in range(3))
        self._driven = np.isin(np.arange(3), self.dofs).astype(float) if len(self.dofs) < 3 else None

    def between(self) -> None:
        self.backend.forces_into(self.ids, self._F)
        self._v[...] = self.velocity((self.k + 0.5) * self.dt)  # one velocity for all (3,), or one each
        np.multiply(self._F, self._v, out=self._Fv)
        if self._driven is not None:
            self._Fv *= self._driven
        self.work -= float(self._Fv.sum()) * self.dt  # midpoint rule, driven DOFs
        self.backend.set_velocities(self.ids, self._v)
        self.k += 1


def dem_only(p: dict, scene: DemScene, dem: str, t_end_default: float,
             drive: tuple[np.ndarray, Callable[[float], np.ndarray]] | None = None, history_every: int = 0,
             dt: float = 0.0, models: tuple = (), drive_dofs: str = "xyz"):
    """(Simulation, backend, PrescribedParticles or None) for ``scene`` alone, driven on
    drive[0] with velocity drive[1](t) if given; dt: the step if the scene sets it (s);
    models: coupling-layer models on the engine's particles (LawBonds, ParticleImpactor);
    drive_dofs: the translations the drive prescribes (the others stay free)."""
    steps = [0]  # hook calls so far (the models' first call has no step behind it)
    try:
        backend = make_backend(dem, p["dem.process"], p["dem.ranks"])
    except EngineUnavailable as exc:
        raise CaseError(str(exc)) from None
    try:
        backend.build(scene)
        if models and not hasattr(backend, "add_forces"):
            raise NotImplementedError("bond laws and impactors evaluated by the coupling layer need added particle forces")
        dt_stable = min(backend.critical_dt(), models_critical_dt(models, scene))
        n, dt = n_steps(p, t_end_default, min(dt, dt_stable) if dt else time_step(p, dt_stable))
        driver = PrescribedParticles(backend, drive[0], drive[1], dt, drive_dofs) if drive else None
        substages = []  # inside the engine's hook, in order
        # in an engine's worker the models run there (their copies here synced before reads)
        hosted = hosted_by(backend, models)
        if models and not hosted:
            view, order = ModelStep(backend, list(models)), list(models)

            def laws():
                view.run(order, dt if steps[0] else 0.0)
                steps[0] += 1
            substages.append(Stage("laws", "models", laws))  # first: the drive reads their forces
        if driver:
            substages.append(Stage("drive", "dem", driver.between))
        hook = (lambda: run_stages(substages)) if substages else None
        backend.set_dt(dt)
        backend.start(hook)
        for stage in substages:  # the first hook ran at set-up, outside the clock's stages
            stage.seconds = 0.0
        if hasattr(backend, "reset_worker_seconds"):  # a worker's start (its set-up) is not the run's
            backend.reset_worker_seconds()
    except NotImplementedError as exc:
        backend.finalize()
        raise CaseError(f"--dem {dem}: {exc}") from None
    except BaseException:
        backend.finalize()
        raise
    def energies():
        d = backend.energies()
        work = 0.0
        if driver:  # the drive's work up to the move that follows the last force evaluation
            F, v = backend.forces(driver.ids)[:, driver.dofs], backend.velocities()[driver.ids][:, driver.dofs]
            work = driver.work - float(np.sum(-F * v)) * dt
        e = [m.energies() for m in models]
        return {"kinetic": d["kinetic"] + sum(x["kinetic"] for x in e), "internal": d["elastic"] + sum(x["internal"] for x in e),
                "external_work": work + sum(x.get("external_work", 0.0) for x in e), "dissipated": d["dissipated"] + sum(x["dissipated"] for x in e)}

    pts0 = scene.x

    def fields() -> FieldFrame:
        return FieldFrame(pts0, {"vertex": np.arange(scene.n)[:, None]},
                          {"displacement": backend.positions() - scene.x, "radius": scene.radius})

    sim = Simulation(
        stages=[Stage("engine.step", "dem", lambda: backend.advance(hook), substages=substages,
                      repeat=lambda steps: backend.advance(hook, steps))], dt=dt, n_steps=n,
        history_every=history_every or p["output.history_every"] or max(1, n // 1000), probes={}, energies=energies,
        counts={"fem_nodes": 0, "fem_elements": 0, "particles": scene.n, "bonds": len(scene.bonds),
                "interface_particles": 0, "law_bonds": sum(len(m.pairs) for m in models if hasattr(m, "pairs")),
                **rank_shares(backend, hosted)},
        clock_info={"dt_fem": 0.0, "dt_dem": dt, "dt_stable_dem": dt_stable, "substeps": 1},
        fields=fields, field_frames=p["output.field_frames"], energy_growth_tol=p["guards.energy_growth"],
        close=backend.finalize, versions={dem: backend.version},
        checkpoint=(lambda: (_state(driver, models, steps), lambda d: backend.checkpoint(d / backend.restart_file)))
        if backend.supports_checkpoint else None,
        restore=lambda state, d: _restore(state, driver, models, steps, backend, d / backend.restart_file, hosted),
        timing_correction=lambda: worker_seconds(backend),
        sync=(lambda: backend.sync_models(models)) if hosted else None)
    return sim, backend, driver


def _state(driver, models, steps) -> dict:
    """What a checkpoint of a DEM-only run holds besides the engine's own restart file."""
    d = {"hook_steps": steps[0], "models": [m.checkpoint_state() for m in models]}
    if driver:
        d["driver"] = {"k": driver.k, "work": driver.work}
    return d


def _restore(d: dict, driver, models, steps, backend, engine_file, hosted: bool = False) -> None:
    steps[0] = int(d["hook_steps"])
    for m, state in zip(models, d.get("models", [])):
        m.restore_state(state)
    if hosted:
        backend.set_models_state(d.get("models", []))
    if driver:
        driver.k, driver.work = int(d["driver"]["k"]), float(d["driver"]["work"])
    backend.restore(engine_file)


def rank_shares(backend, hosted: bool) -> dict:
    """{"law_bonds_per_rank": [...]}: the law bonds each MPI rank of an engine's worker
    evaluates (the models hosted on several ranks, dem_region/rank_laws.py), else {}."""
    if not hosted or getattr(backend, "ranks", 1) < 2:
        return {}
    return {"law_bonds_per_rank": [sum(s) for s in backend.law_shares()]}


def worker_seconds(dem) -> dict[str, float]:
    """The timing buckets of an engine in a worker besides its own time ({} in process): its
    hosted models, its interface reads and writes, its transport; "dem" less all of them."""
    if not hasattr(dem, "worker_seconds"):
        return {}
    out = dict(dem.worker_seconds())
    out["dem"] = -sum(out.values())
    out["compile"] = dem.compile_seconds()  # (within the buckets and the total: not one of them)
    return out


def models_critical_dt(models, scene: DemScene) -> float:
    """Stable step (s) of the engine's bonds, the coupling layer's law bonds and the impactors'
    penalties on the particles together (their springs add on the same particles: a top
    particle under a rod carries its bonds and the rod's penalty; Gershgorin's bound,
    compressive stiffness), and of each impactor's own contact mode."""
    if not models:
        return np.inf
    laws = [b for b in models if hasattr(b, "pairs")]
    others = [m.critical_dt(scene.mass) for m in models if not hasattr(m, "pairs")]
    ground = np.zeros(scene.n)
    for m in models:
        if hasattr(m, "ground_stiffness"):
            ground += m.ground_stiffness(scene.n)
    pairs = [scene.bonds] + [b.pairs for b in laws]
    k = [np.maximum(scene.kn, scene.ks)] + [np.broadcast_to(b.law.K, (len(b.pairs),)) * b.area for b in laws]
    return min(gershgorin_dt(scene.mass, np.vstack(pairs), np.concatenate(k), ground), *others, np.inf)


def particles_escaped(backend, scene: DemScene, factor: float = 2.0):
    """A guard: particles farther from the zone's centre than ``factor`` times its initial
    half-diagonal have left the damage zone (a blown-up bond, or an interface that lets go)."""
    centre = 0.5 * (scene.x.min(axis=0) + scene.x.max(axis=0))
    reach = factor * max(float(np.linalg.norm(scene.x.max(axis=0) - centre)), float(scene.radius.max()))

    def check():
        d = np.linalg.norm(backend.positions() - centre, axis=1)
        out = np.flatnonzero(d > reach)
        if out.size:
            return (f"DEM: {out.size} particle(s) left the damage zone, first {out[0]} at "
                    f"{np.round(backend.positions()[out[0]], 6).tolist()} m (unstable bonds or interface)")
        return None
    return check


def hold_symmetry_planes(backend, i: np.ndarray, j: np.ndarray, held: np.ndarray) -> None:
    """Particles on the planes x = 0 (column i == 0) and y = 0 (j == 0) of a quarter model
    keep x, y or both at rest; ``held``: particles another constraint drives (tie, clamp)."""
    for dofs, on in (("xy", (i == 0) & (j == 0)), ("x", (i == 0) & (j > 0)), ("y", (j == 0) & (i > 0))):
        ids = np.setdiff1d(np.flatnonzero(on), held)
        backend.prescribe(ids, dofs)
        backend.set_velocities(ids, np.zeros((len(ids), 3)))
