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


def assert_same_states(back: list[dict], states: list[dict]) -> None:
    """``back`` holds ``states`` bit for bit: the same keys, arrays of the same dtype, shape
    and bytes, scalars of the same type and value."""
    for d, b in zip(states, back, strict=True):
        assert set(b) == set(d)
        for k, v in d.items():
            if isinstance(v, np.ndarray):
                assert b[k].dtype == v.dtype and b[k].shape == v.shape and b[k].tobytes() == v.tobytes()
            else:
                assert type(b[k]) is type(v) and b[k] == v


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
        assert_same_states(back, states)
        # the block holds only the numeric entries, each on a float64 boundary
        at, size = state_block.offsets(entries)
        assert all(o % 8 == 0 for o in at) and size >= 8
    finally:
        reader.close()
        writer.close()
        writer.unlink()


def _mutated(states: list[dict], how: int) -> list[dict]:
    """``states`` changed one way: 0 none, 1 an array's shape, 2 its dtype, 3 a float made an
    int, 4 a key added, 5 a value that is not numeric, 6 a key dropped, 7 a model added."""
    out = [dict(d) for d in states]
    d = out[0]
    arrays = [k for k, v in d.items() if isinstance(v, np.ndarray)]
    if how == 1 and arrays:
        d[arrays[0]] = np.zeros(d[arrays[0]].size + 1, d[arrays[0]].dtype)
    elif how == 2 and arrays:
        d[arrays[0]] = d[arrays[0]].astype(np.complex128 if d[arrays[0]].dtype == np.float64 else np.float64)
    elif how == 3:
        d["work"] = 1
    elif how == 4:
        d["extra"] = 1.0
    elif how == 5:
        d["work"] = "one"
    elif how == 6:
        del d["work"]
    elif how == 7:
        out.append({"work": 0.0})
    return out


@given(st.data())
@settings(max_examples=60, deadline=None)
def test_states_are_written_at_the_end_of_an_advance_only_when_they_fit_the_block(data):
    """state_block.write_if_fits (the worker's side of a sync after an advance's last step)
    writes exactly when the states' layout is the block's and nothing lies beside it, and what
    it wrote reads back bit for bit; otherwise it writes nothing (the sync then asks over the
    socket)."""
    from dem_region import state_block
    states = []
    for _ in range(data.draw(st.integers(1, 3))):
        d = {f"a{k}": data.draw(hnp.arrays(data.draw(DTYPES), hnp.array_shapes(min_dims=0, max_dims=2, max_side=4)))
             for k in range(data.draw(st.integers(0, 3)))}
        d["work"], d["count"], d["flag"] = data.draw(st.floats(allow_nan=False)), data.draw(st.integers(-9, 9)), True
        states.append(d)
    entries, _ = state_block.layout(states)
    buf = bytearray(state_block.offsets(entries)[1])
    on = state_block.views(buf, entries)
    other = _mutated(states, data.draw(st.integers(0, 7)))
    new_entries, rest = state_block.layout(other)
    fits = new_entries == entries and not any(rest)
    before = bytes(buf)
    assert state_block.write_if_fits(on, entries, other) == fits
    if not fits:
        assert bytes(buf) == before
        return
    back = state_block.read(on, entries, [{} for _ in other])
    assert_same_states(back, other)


def test_every_hosted_model_keeps_copies_of_a_sync_read_as_views():
    """The sync after an advance hands set_model_states views on the shared block, which the
    next sync rewrites: each hosted model (law bonds, a particle impactor, a particle load)
    keeps copies, so rewriting the block leaves the restored models' states as they were."""
    from dem_region import state_block
    from dem_region.model_step import model_states, set_model_states
    from dem_region.particle_impactor import ParticleImpactor
    from dem_region.particle_load import ParticleLoad
    from physics.impactor import RigidImpactor
    from physics.law_bonds import LawBonds
    from physics.laws import HashinCohesiveLaw

    def made(seed):
        rng = np.random.default_rng(seed)
        X = rng.normal(size=(4, 3)) * 1e-3
        law = HashinCohesiveLaw(K=1e14, Z0=80e6, R0=100e6, GIc=969.0, GIIc=1719.0, eta=2.284)
        bonds = LawBonds([[0, 1], [2, 3]], X, [[0.0, 1.0, 0.0]] * 2, 1e-6, law, friction=0.4)
        bonds.damage, bonds.delta = rng.random(2), rng.normal(size=bonds.delta.shape)
        imp = ParticleImpactor(RigidImpactor("sphere", rng.normal(size=3), 0.01, 1.0, rng.normal(size=3), 1e6), [0, 1])
        imp._x_prev, imp.force = rng.normal(size=(2, 3)), rng.normal(size=3)
        load = ParticleLoad([2, 3], rng.normal(size=(2, 3)), lambda t: 1.0)
        load._f_prev, load.work = rng.normal(size=(2, 3)), float(rng.normal())
        return [bonds, imp, load]

    source, copies = made(1), made(2)
    states = model_states(source)
    entries, rest = state_block.layout(states)
    assert not any(rest)
    buf = bytearray(state_block.offsets(entries)[1])
    on = state_block.views(buf, entries)
    assert state_block.write_if_fits(on, entries, states)
    set_model_states(copies, state_block.read(on, entries, [{} for _ in copies], copy=False))
    restored = [{k: np.array(v, copy=True) for k, v in d.items()} for d in model_states(copies)]
    buf[:] = b"\xff" * len(buf)  # the next sync rewrites the block
    for d, was, want in zip(model_states(copies), restored, states):
        for k in want:
            assert np.asarray(d[k]).tobytes() == np.asarray(was[k]).tobytes() == np.asarray(want[k]).tobytes(), k
