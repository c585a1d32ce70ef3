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
RUN = {"clock.t_end": 1.2e-5, "output.history_every": 100000, "output.field_frames": 0}


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


def _stage_peaks(mode: str, dem: str, size: dict, name: str = "beam_impact_coarse") -> tuple[dict, dict]:
    """({stage: median transient bytes over the steps after the first ten}, counts)."""
    case = load_case(name, {**size, **RUN})
    sim = case.scene.build(case.parameters, mode, dem)
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
