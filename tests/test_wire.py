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
