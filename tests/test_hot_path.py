"""The per-step hot path allocates nothing that grows with the model.

Each stage of a clock step (the engine's step and the stages in its hook, the FEM's kicks,
drift and forces with loads, supports and damping, the interface's read and write, the laws) is measured by tracemalloc, which
numpy reports its arrays to: the stage's transient peak above the memory held before it, the
median over the steps. Python's own small objects remain (a compiled call's boxed arguments,
floats: about 3 kB a stage whatever the size), so the check is against the model's size: the
same case at twice the particles and twice the FEM nodes must not raise any stage's peak by a
quarter of its smallest array (one coordinate per particle, or per node). Any array of the
model's particles, nodes or bonds made in a step fails it (`np.take(..., out=)` under its
default mode, a broadcast `np.divide(..., out=)`, `u += dt * v`: each a temporary of its size).
YADE is left out: its Python API hands the positions over as new lists at every read
(coordsAndDisplacements, one coordinate of every sphere a call), which no adapter can avoid."""
import statistics
import tracemalloc

import pytest

from coupling.case import load_case
from coupling.simulation import run_clock

# the coarse seed beam (an impactor, clamps, a cohesive far field) at two sizes
SMALL = {"geometry.span": 40e-3, "zone.half_width": 5e-3, "mesh.elements_along": 20}
LARGE = {"geometry.span": 80e-3, "zone.half_width": 10e-3, "mesh.elements_along": 40}
# a few hundred steps; a history sample (the ledger's snapshot) at none of them after the first
# (set on the built model: a case's output.history_every leaving fewer than 10 samples is refused)
RUN = {"clock.t_end": 1.2e-5, "output.field_frames": 0}


def _measured(stage, peaks: dict) -> None:
    """Wrap ``stage.run`` (and its substages') to record each call's transient peak in bytes."""
    for sub in stage.substages:
        _measured(sub, peaks)
    run, record = stage.run, peaks.setdefault(stage.name, [])

    def measured():
        held, _ = tracemalloc.get_traced_memory()
        tracemalloc.reset_peak()
        run()
        record.append(tracemalloc.get_traced_memory()[1] - held)
    stage.run = measured
    if stage.repeat is not None:  # one step per call, so that each is measured
        stage.repeat = None


def _stage_peaks(mode: str, dem: str, size: dict, name: str = "beam_impact_coarse", settings: dict = {}) -> tuple[dict, dict]:
    """({stage: median transient bytes over the steps after the first ten}, counts)."""
    case = load_case(name, {**size, **RUN, **settings})
    sim = case.scene.build(case.parameters, mode, dem)
    # the guards judge the model, not its stages' allocations: with the viscous hourglass form
    # (no stiffness on the hourglass modes) this beam of one-point elements hourglasses, which
    # its guard stops at the first sample
    sim.guards = []
    sim.history_every = sim.n_steps  # one sample at the end (and a coupled clock's snapshot with it)
    for stage in sim.stages:
        clock = getattr(stage.run, "__self__", None)
        if hasattr(clock, "snapshot_every"):
            clock.snapshot_every = sim.n_steps
    peaks: dict[str, list[int]] = {}
    for stage in sim.stages:
        _measured(stage, peaks)
    tracemalloc.start()
    try:
        run_clock(sim)
    finally:
        tracemalloc.stop()
        sim.close()
    return {k: statistics.median(v[10:]) for k, v in peaks.items() if len(v) > 20}, sim.counts


@pytest.mark.parametrize("mode, dem", [("fem", "liggghts"), ("dem", "liggghts"), ("coupled", "liggghts"),
                                       ("coupled", "lammps")])
def test_no_stage_allocates_with_the_model(mode, dem):
    _same_at_both_sizes(_stage_peaks(mode, dem, SMALL), _stage_peaks(mode, dem, LARGE))


# the 3D strip at two zone widths and spans (more particles and more nodes): its cylinder lies
# along the width, a contact of its own (an axis), which the 2D beams' disc does not take
SMALL_3D = {"geometry.span": 40e-3, "zone.half_width": 3.6e-3, "mesh.elements_along": 10}
LARGE_3D = {"geometry.span": 80e-3, "zone.half_width": 6e-3, "mesh.elements_along": 20}


def test_no_stage_allocates_with_the_3d_model():
    _same_at_both_sizes(*(_stage_peaks("coupled", "liggghts", size, "beam_impact_3d_coarse")
                          for size in (SMALL_3D, LARGE_3D)))


def test_no_stage_allocates_with_the_model_under_a_flat_face():
    """The all-FEM rod_impact: its rod, a flat face with a footprint per node (it took 54 kB a
    step before session 49 compiled it), on the coarse plate at two radial resolutions."""
    _same_at_both_sizes(*(_stage_peaks("fem", "liggghts", {"mesh.elements_along": n}, "rod_impact_coarse")
                          for n in (8, 16)))


# the paths a case file may choose beyond the defaults: the penalty tie; several DEM steps per
# FEM step (the interface band's elements among the fast forces, linear and Total Lagrangian);
# one-point elements with the stiffness or the viscous hourglass control (the band's elements are
# the interface's, not the model's: its Total Lagrangian form writes into a buffer of its own)
OPTIONS = {
    "penalty tie": ("coupled", {"coupling.tie": "penalty", "clock.substeps": 2}),
    "band, linear": ("coupled", {"clock.substeps": 3}),
    "TL, hourglass stiffness": ("fem", {"fem.formulation": "total_lagrangian", "fem.integration": "reduced",
                                        "fem.hourglass": "stiffness", "clock.t_end": 6e-6}),
    "TL, hourglass viscous": ("fem", {"fem.formulation": "total_lagrangian", "fem.integration": "reduced",
                                      "fem.hourglass": "viscous", "clock.t_end": 6e-6}),
}


@pytest.mark.parametrize("option", OPTIONS)
def test_no_stage_allocates_with_the_model_on_the_options(option):
    mode, settings = OPTIONS[option]
    _same_at_both_sizes(*(_stage_peaks(mode, "liggghts", size, settings=settings) for size in (SMALL, LARGE)))


def test_no_stage_allocates_with_the_model_under_loads_and_damping():
    """The cantilever's tip load and its mass-proportional damping (dynamic relaxation)."""
    sizes = ({"mesh.elements_along": 40, "mesh.elements_through": 2}, {"mesh.elements_along": 80, "mesh.elements_through": 4})
    _same_at_both_sizes(*(_stage_peaks("fem", "liggghts", size, "cantilever") for size in sizes))


def _same_at_both_sizes(small_run: tuple, large_run: tuple) -> None:
    (small, n_small), (large, n_large) = small_run, large_run
    assert set(small) == set(large) and small, "the same stages at both sizes"
    # the smallest array a step could make of the larger model: one float per particle or node
    grew = [8 * (n_large[k] - n_small[k]) for k in ("particles", "fem_nodes") if n_large[k] > n_small[k]]
    assert grew and min(grew) >= 8 * 100, (n_small, n_large)
    for name in small:
        assert large[name] - small[name] < min(grew) / 4, \
            f"stage {name}: {small[name]:.0f} B a step at {n_small}, {large[name]:.0f} B at {n_large}"


def _force_evaluation_peak(dyn) -> float:
    """Median transient bytes of the FEM's force evaluation over 30 steps of ``dyn`` (started),
    after the first ten."""
    dt, peaks = 0.5 * dyn.critical_dt(), []
    tracemalloc.start()
    try:
        for _ in range(30):
            dyn.kick_drift(dt)
            held, _ = tracemalloc.get_traced_memory()
            tracemalloc.reset_peak()
            dyn.compute_forces()
            peaks.append(tracemalloc.get_traced_memory()[1] - held)
            dyn.kick(dt)
    finally:
        tracemalloc.stop()
    return statistics.median(peaks[10:])


def test_the_fem_step_allocates_nothing_under_stiffness_damping_and_bulk_viscosity():
    """Stiffness-proportional (beta) damping, the bulk viscosity and the viscous hourglass
    control, which no case file reaches (library options of ExplicitDynamics): the FEM's force
    evaluation of a compressed block at two sizes."""
    import numpy as np

    from fem_region import materials, mesh
    from fem_region.bulk_viscosity import BulkViscosity
    from fem_region.elements import ELEMENTS
    from fem_region.explicit import ExplicitDynamics
    from fem_region.region import FemRegion

    def peak(n: int) -> tuple[float, int]:
        m = mesh.rectangle(np.linspace(0, 0.1, n + 1), np.linspace(0, 0.05, n // 2 + 1))
        D = materials.reduce(materials.isotropic(1e9, 0.3), 2, "plane_strain")
        r = FemRegion(m, ELEMENTS["quad4"], D, 1000.0, 0.01, "reduced", hourglass="viscous")
        dyn = ExplicitDynamics(r, beta=1e-7, bulk_viscosity=BulkViscosity.of(r))
        dyn.state.v[:] = -(r.X - r.X.mean(axis=0))  # compressed: the bulk viscosity acts
        dyn.start()
        bytes_ = _force_evaluation_peak(dyn)
        assert dyn.ledger.damping != 0.0  # the damping forces did work
        return bytes_, r.n_nodes

    (small, n_small), (large, n_large) = peak(20), peak(40)
    assert large - small < 8 * (n_large - n_small) / 4, (small, large)


def test_the_fem_step_allocates_nothing_under_a_moving_support():
    """A support whose velocity changes with time (the panel's end shortening: its
    acceleration by central difference at each force evaluation, the reaction's work) beside a
    clamped end, the FEM's force evaluation of a strip at two sizes."""
    import numpy as np

    from fem_region import materials, mesh
    from fem_region.elements import ELEMENTS
    from fem_region.explicit import ExplicitDynamics, PrescribedMotion
    from fem_region.region import FemRegion

    def peak(n: int) -> tuple[float, int]:
        m = mesh.rectangle(np.linspace(0, 0.1, n + 1), np.linspace(0, 0.01, 3))
        D = materials.reduce(materials.isotropic(1e9, 0.3), 2, "plane_strain")
        r = FemRegion(m, ELEMENTS["quad4"], D, 1000.0, 0.01)
        left, right = (np.flatnonzero(np.isclose(r.X[:, 0], x)) for x in (0.0, 0.1))
        dyn = ExplicitDynamics(r, supports=[PrescribedMotion(np.concatenate([2 * left, 2 * left + 1])),
                                            PrescribedMotion(2 * right, lambda t: -1e3 * t)])
        dyn.start()
        bytes_ = _force_evaluation_peak(dyn)
        assert dyn.ledger.support_work != 0.0  # the moving end did work
        return bytes_, r.n_nodes

    (small, n_small), (large, n_large) = peak(200), peak(800)
    assert large - small < 8 * (n_large - n_small) / 4, (small, large)
