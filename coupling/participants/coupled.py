"""The coupled assembly: FEM participant, engine, transition interface and tie, the shared
clock's step and substep count, outputs and guards, as one Simulation."""
from __future__ import annotations

from typing import Callable

import numpy as np

from dem_region.backends import EngineUnavailable, make_backend
from dem_region.scene import DemScene
from fem_region.explicit import ExplicitDynamics
from interfaces.ties import KinematicTie, PenaltyTie
from interfaces.transition import InterfaceError, TransitionInterface

from ..params import CaseError, Param
from ..simulation import FieldFrame, Simulation
from ..timestep import n_steps, time_step
from .clock import CoupledClock
from .dem import models_critical_dt, particles_escaped, rank_shares
from .fem import fem_guards


# parameters every coupled scene takes (spread into its PARAMETERS)
COUPLING: dict[str, Param] = {
    "coupling.tie": Param("kinematic", "tie scheme: kinematic (interface particles slaved to the FEM) or "
                           "penalty (springs to their host points, the seed paper's transition contact)",
                           kind="str", choices=("kinematic", "penalty")),
    "coupling.tie_penalty": Param(0.0, "penalty tie stiffness per particle; 0 = 4 x the stiffest bond", unit="N/m", low=0.0),
}


def coupled_simulation(p: dict, make_fem: Callable[[np.ndarray | None], ExplicitDynamics], scene: DemScene,
                       dem: str, t_end_default: float, history_every: int = 0, steps: int = 0, models: tuple = (),
                       start: Callable | None = None, hold: Callable | None = None, engine=None,
                       engine_scene: DemScene | None = None):
    """(Simulation, CoupledClock) for a FEM far field made by ``make_fem(None)`` and a
    DEM ``scene`` whose group "interface" is slaved to the FEM. steps: FEM steps (default
    from t_end); history_every: FEM steps between samples (default from output.history_every);
    start: a state to continue from (a grown zone's, coupling/study/growth.py), called as
    start(fem, scene, interface, models) once both participants exist and before the engine
    is built; it sets the FEM's and the models' state and returns the scene the engine starts
    from (the particles' current positions and velocities; ``scene`` keeps the reference ones);
    hold: called with the engine once it is built and tied, before it starts (a quarter's
    symmetry planes: held from its first evaluation, which a grown zone's model makes with the
    particles in motion).
    Seeded particles (``scene.groups["dormant"]``: a growing zone's reserve, in the engine from
    the start) are slaved to the FEM as the interface's are, but carry none of the model's mass
    (the FEM's elements do) and no force (no law bond reaches them); engine_scene: the scene the
    engine is built with when its masses differ (a seeded particle's own, for when it is
    released); engine: an engine already running those particles, continued on (a seeded zone
    grown: ``start`` then writes its state into it and returns None)."""
    fem = make_fem(None)  # built once; the tie's node masses are added below
    dormant = scene.groups.get("dormant", np.zeros(0, int))
    try:
        itf = TransitionInterface.build(fem.region, scene.x, np.concatenate(
            [scene.groups.get("interface", np.zeros(0, int)), dormant]).astype(int))
    except InterfaceError as exc:
        raise CaseError(f"interface: {exc}") from None
    if p["coupling.tie"] == "kinematic":
        if not scene.placeholder_bonds:
            # the FEM carries the band's stiffness (placeholder bonds carry none and must
            # stay: without them an engine adds contact between overlapping law pairs)
            scene = scene.without_bonds_within(itf.ids)
        carried = scene.mass.copy()
        carried[dormant] = 0.0
        fem.add_nodal_mass(itf.share_mass(carried[itf.ids]))  # slaved particles move with the nodes
    engine_scene = scene if engine_scene is None else engine_scene
    engine_scene = start(fem, engine_scene, itf, models) if start is not None else engine_scene
    if engine is not None:
        return _assemble(p, fem, itf, scene, engine, dem, t_end_default, history_every, steps, models, None, None)
    try:  # the engine last, so a bad interface never leaves an engine or worker behind
        backend = make_backend(dem, p["dem.process"], p["dem.ranks"])
    except EngineUnavailable as exc:
        raise CaseError(str(exc)) from None
    try:
        return _assemble(p, fem, itf, scene, backend, dem, t_end_default, history_every, steps, models, engine_scene,
                         hold)
    except NotImplementedError as exc:
        backend.finalize()
        raise CaseError(f"--dem {dem}: {exc}") from None
    except BaseException:
        backend.finalize()  # never leave an engine (or its worker process) behind
        raise


def _assemble(p, fem, itf, scene, backend, dem, t_end_default, history_every, steps, models, engine_scene, hold):
    if engine_scene is not None:  # (None: an engine already running, its planes held)
        backend.build(engine_scene)
    if p["coupling.tie"] == "kinematic":
        tie = KinematicTie(itf, backend, scene.mass, seeded=len(scene.groups.get("dormant", ())))
    else:
        if not hasattr(backend, "add_forces"):
            raise NotImplementedError("the penalty tie needs added particle forces, not available on this engine yet")
        tie = PenaltyTie(itf, backend, scene.mass, p["coupling.tie_penalty"] or 4 * float(scene.kn.max()))
    if hold is not None:
        hold(backend)
    dt_fem, dt_dem = fem.critical_dt(), min(backend.critical_dt(), tie.critical_dt(fem.m),
                                            models_critical_dt(models, scene))
    # 0 = automatic: as many substeps as the FEM step allows (with the interface band's
    # elements among the fast forces the impulse scheme does not resonate: coupling/participants/clock.py;
    # the penalty tie resonated at m = 4, k = 2e8 N/m before the band, tests/test_coupled.py)
    auto = max(1, int(np.floor(dt_fem / dt_dem)))
    m = p["clock.substeps"] or auto
    n, dt = n_steps(p, t_end_default, time_step(p, min(dt_fem, m * dt_dem)))
    if steps:
        n, dt = steps, time_step(p, min(dt_fem, m * dt_dem))
    if dt / m > dt_dem:
        raise CaseError(f"clock.dt = {p['clock.dt']:g}: the DEM substep dt/{m} is above the DEM stable step "
                        f"{dt_dem:.4g} s; allowed <= {m * dt_dem:.4g} s")
    if models and not hasattr(backend, "add_forces"):
        raise NotImplementedError("bond laws and impactors evaluated by the coupling layer need added particle forces")
    clock = CoupledClock(fem, backend, tie, dt, m, models=models)
    every = history_every or p["output.history_every"] or max(1, n // 1000)
    clock.snapshot_every, clock.last_window = every, n
    region = fem.region
    pts0 = np.vstack([np.pad(region.X, ((0, 0), (0, 3 - region.dim))), scene.x])
    cell = {"quad4": "quad", "tri3": "triangle", "hex8": "hexahedron", "tet4": "tetra"}[region.etype.name]
    cells = {cell: region.mesh.t.T, "vertex": (region.n_nodes + np.arange(scene.n))[:, None]}

    def fields() -> FieldFrame:
        u = np.vstack([np.pad(fem.state.u, ((0, 0), (0, 3 - region.dim))), backend.positions() - scene.x])
        radius = np.concatenate([np.zeros(region.n_nodes), scene.radius])
        return FieldFrame(pts0, cells, {"displacement": u, "radius": radius})

    sim = Simulation(
        stages=clock.stages(), dt=dt, n_steps=n,
        history_every=every,
        probes={"interface_work": lambda: clock.interface_work_snapshot,
                **{f"momentum_{c}": (lambda i=i: float(clock.momentum()[i])) for i, c in enumerate("xyz")}},
        energies=clock.energies,
        counts={"fem_nodes": region.n_nodes, "fem_elements": region.n_elements, "particles": scene.n,
                "bonds": len(scene.bonds), "interface_particles": len(itf.ids) - len(scene.groups.get("dormant", ())),
                **({"seeded_particles": len(scene.groups["dormant"])} if "dormant" in scene.groups else {}),
                "law_bonds": sum(len(m.pairs) for m in models if hasattr(m, "pairs")),
                **rank_shares(backend, clock.hosted)},
        clock_info={"dt_fem": dt, "dt_dem": dt / m, "dt_stable_fem": dt_fem, "dt_stable_dem": dt_dem, "substeps": m},
        fields=fields, field_frames=p["output.field_frames"], energy_growth_tol=p["guards.energy_growth"],
        close=backend.finalize, versions={dem: backend.version}, timing_correction=clock.timing_correction,
        instability_hint=_hint(p, tie, m, dt, dt_dem),
        guards=fem_guards(fem) + [particles_escaped(backend, scene)],
        checkpoint=(lambda: (clock.checkpoint_state(), lambda d: backend.checkpoint(d / backend.restart_file)))
        if backend.supports_checkpoint else None,
        restore=lambda state, d: clock.restore_state(state, d / backend.restart_file),
        sync=clock.sync_models if clock.hosted else None)
    return sim, clock


def _hint(p: dict, tie, m: int, dt: float, dt_dem_stable: float) -> str:
    """What to try when a coupled run goes unstable."""
    if m == 1:
        return f"check the time step (clock.safety = {p['clock.safety']:g}) and the interface"
    omega = 2.0 / dt_dem_stable  # the fastest DEM-side mode
    return (f"{m} DEM substeps per FEM step of {dt:.3g} s = {dt * omega / np.pi:.1f} half-periods of the fastest "
            f"DEM mode ({tie.name} tie): impulse time stepping resonates near whole periods; try "
            "clock.substeps=1 or another substep count")
