"""Python objects across the worker boundary, whichever numpy each side runs.

The orchestrator runs Debian's numpy 1.24, the LAMMPS worker the wheel's numpy 2: a numpy 2
pickle of an array names ``numpy._core``, which numpy 1 cannot import. Here every array and
numpy scalar is pickled as (dtype, shape, bytes) and rebuilt by a function of this module, so
objects holding arrays (the coupling layer's models, their states) travel both ways bit for
bit.
"""
from __future__ import annotations

import io
import pickle
import warnings

import numpy as np


def _array(dtype: str, shape: tuple, data: bytes) -> np.ndarray:
    return np.frombuffer(data, dtype=np.dtype(dtype)).reshape(shape).copy()


def _scalar(dtype: str, data: bytes):
    return np.frombuffer(data, dtype=np.dtype(dtype))[0]


class _Pickler(pickle.Pickler):
    def reducer_override(self, obj):
        if type(obj) is np.ndarray and obj.dtype != object:
            return _array, (obj.dtype.str, obj.shape, np.ascontiguousarray(obj).tobytes())
        if isinstance(obj, np.generic) and not isinstance(obj, np.object_):
            return _scalar, (obj.dtype.str, obj.tobytes())
        return NotImplemented


def dumps(obj) -> bytes:
    buf = io.BytesIO()
    _Pickler(buf, protocol=pickle.HIGHEST_PROTOCOL).dump(obj)
    return buf.getvalue()


def loads(data: bytes):
    with warnings.catch_warnings():  # a dtype or type pickled by the other numpy may warn on load
        warnings.simplefilter("ignore", DeprecationWarning)
        return pickle.loads(data)

