"""Objects across the worker boundary (dem_region/wire.py): every array and numpy scalar
arrives bit for bit, in both directions between the orchestrator's numpy 1 and the LAMMPS
worker's numpy 2 (a plain pickle of a numpy 2 array does not load under numpy 1)."""
import subprocess
from pathlib import Path

import numpy as np
from hypothesis import given, settings, strategies as st
from hypothesis.extra import numpy as hnp

from dem_region import wire
from dem_region.backends import LAMMPS_VENV

DTYPES = st.sampled_from([np.float64, np.float32, np.int64, np.int32, np.bool_, np.uint8])


@given(st.data())
@settings(max_examples=60, deadline=None)
def test_arrays_and_scalars_round_trip_bit_for_bit(data):
    dtype = data.draw(DTYPES)
    a = data.draw(hnp.arrays(dtype, hnp.array_shapes(min_dims=0, max_dims=3, max_side=5)))
    obj = {"a": a, "view": a.T, "scalar": a.dtype.type(a.flat[0]) if a.size else dtype(0), "nested": [a, (1.5, "x")]}
    back = wire.loads(wire.dumps(obj))
    for k in ("a", "view"):
        assert back[k].dtype == obj[k].dtype and back[k].shape == obj[k].shape
        assert back[k].tobytes() == np.ascontiguousarray(obj[k]).tobytes()
    assert back["scalar"].tobytes() == obj["scalar"].tobytes() and back["nested"][1] == (1.5, "x")


def test_the_other_numpy_reads_and_writes_what_this_one_does():
    """A payload from here is loaded by the LAMMPS venv's python (numpy 2), changed there and
    sent back: NaN payloads, negative zero and the largest floats survive both trips."""
    a = np.array([np.nan, -0.0, np.finfo(float).max, 1e-310, 1.0 / 3.0])
    script = ("import sys; from dem_region import wire; import numpy as np; d = wire.loads(sys.stdin.buffer.read()); "
              "d['b'] = d['a'] * 2; sys.stdout.buffer.write(wire.dumps(d))")
    python = LAMMPS_VENV / "bin" / "python"
    done = subprocess.run([str(python), "-c", script], input=wire.dumps({"a": a}), capture_output=True,
                          cwd=str(Path(wire.__file__).parents[1]))
    assert done.returncode == 0, done.stderr.decode()[-500:]
    back = wire.loads(done.stdout)
    with np.errstate(over="ignore"):  # the largest float doubled is inf on both sides
        assert back["a"].tobytes() == a.tobytes() and back["b"].tobytes() == (a * 2).tobytes()


@given(st.data())
@settings(max_examples=40, deadline=None)
def test_model_states_cross_a_shared_block_bit_for_bit(data):
    """dem_region/state_block.py: the hosted models' states written into a shared-memory block
    by one side (its own attachment) and read back by the other are the states, bit for bit:
    arrays of any numeric dtype and shape (0-d too), Python and numpy scalars with their kind,
    and the values that are neither beside the block; what was read survives the block's
    next rewrite."""
    from multiprocessing import resource_tracker, shared_memory

    from dem_region import state_block
    states = []
    for _ in range(data.draw(st.integers(1, 3))):
        d = {}
        for k in range(data.draw(st.integers(0, 4))):
            d[f"a{k}"] = data.draw(hnp.arrays(data.draw(DTYPES), hnp.array_shapes(min_dims=0, max_dims=3, max_side=5)))
        d["work"] = data.draw(st.floats(allow_nan=False))
        d["snapback"] = data.draw(st.integers(-2**62, 2**62))
        d["flag"] = data.draw(st.booleans())
        d["label"] = data.draw(st.text(max_size=5))
        states.append(d)
    entries, rest = state_block.layout(states)
    writer = shared_memory.SharedMemory(create=True, size=state_block.offsets(entries)[1])
    reader = shared_memory.SharedMemory(name=writer.name)  # the other side's attachment
    resource_tracker.unregister(reader._name, "shared_memory")  # noqa: SLF001
    try:
        state_block.write(state_block.views(writer.buf, entries), entries, states)
        back = state_block.read(state_block.views(reader.buf, entries), entries, wire.loads(wire.dumps(rest)))
        writer.buf[:] = bytes(writer.size)  # the next sync rewrites the block: what was read stays
        for d, b in zip(states, back):
            assert set(b) == set(d)
            for k, v in d.items():
                if isinstance(v, np.ndarray):
                    assert b[k].dtype == v.dtype and b[k].shape == v.shape and b[k].tobytes() == v.tobytes()
                else:
                    assert type(b[k]) is type(v) and b[k] == v
        # the block holds only the numeric entries, each on a float64 boundary
        at, size = state_block.offsets(entries)
        assert all(o % 8 == 0 for o in at) and size >= 8
    finally:
        reader.close()
        writer.close()
        writer.unlink()
