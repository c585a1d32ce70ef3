"""The clock loop (coupling/simulation.run_clock): run in blocks of steps up to its next sample,
frame or checkpoint, it samples, draws and saves at exactly the steps a step-by-step loop does,
with the model at that step."""
import numpy as np
from hypothesis import given, settings, strategies as st

from coupling.simulation import FieldFrame, Simulation, Stage, run_clock


@settings(max_examples=25, deadline=None)  # (60 took 16 s of the suite; HYPOTHESIS_PROFILE=explore draws new ones)
@given(n=st.integers(1, 400), every=st.integers(1, 60), frames=st.integers(0, 12), save_every=st.integers(0, 90),
       in_blocks=st.booleans())
def test_blocks_of_steps_sample_draw_and_save_where_the_step_by_step_loop_does(tmp_path_factory, n, every, frames,
                                                                               save_every, in_blocks):
    taken, blocks = [0], []  # clock steps the stage has taken; the blocks it was asked for

    def one():
        taken[0] += 1

    def many(k):
        blocks.append(k)
        taken[0] += k

    seen = {"sample": [], "frame": [], "save": []}
    sim = Simulation(
        stages=[Stage("engine.step", "dem", one, repeat=many if in_blocks else None)], dt=1e-6, n_steps=n,
        history_every=every, probes={"taken": lambda: float(taken[0])},
        energies=lambda: {"kinetic": 1.0, "internal": 0.0, "external_work": 0.0, "dissipated": 0.0},
        fields=lambda: FieldFrame(np.zeros((1, 3)), {"vertex": np.zeros((1, 1), int)}, {}), field_frames=frames,
        checkpoint=lambda: (seen["save"].append(taken[0]) or {"taken": taken[0]}, None))
    result = run_clock(sim, on_sample=lambda step, t: seen["sample"].append((step, taken[0])),
                       on_frame=lambda t, frame: seen["frame"].append((round(t / sim.dt), taken[0])),
                       run_dir=tmp_path_factory.mktemp("run"), checkpoint_every=save_every)

    samples = sorted({s for s in range(0, n + 1, every)} | {n})
    frame_every = max(1, n // frames) if frames else 0
    assert seen["sample"] == [(s, s) for s in samples]
    assert result["history"]["taken"].tolist() == samples == [round(t / sim.dt) for t in result["history"]["time"]]
    assert seen["frame"] == ([(s, s) for s in range(0, n + 1, frame_every)] if frames else [])
    assert seen["save"] == ([s for s in range(save_every, n, save_every)] if save_every else [])
    assert taken[0] == n == result["steps"]
    if in_blocks:  # one call between two consecutive things the loop does, none across one
        stops = sorted({0, *samples, *(s for s, _ in seen["frame"]), *seen["save"]})
        assert blocks == [b - a for a, b in zip(stops, stops[1:]) if b - a > 1]  # (a single step: run)
