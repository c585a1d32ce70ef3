"""The kernels' compile seconds (physics/compile_clock.py): counted once per compilation, a
kernel's callees inside its own; a cache load or a second call adds nothing; a run reports them
(timing_s.compile) within its total, an engine worker's included."""
import time

import numba
import pytest
import numpy as np

from physics.compile_clock import compile_seconds


def _fresh_kernels(tag: float):
    """A kernel and its callee that no process has compiled (a constant of this call in their
    bytecode's closure: new functions, no disk cache)."""
    @numba.njit(cache=False)
    def inner(a):
        return np.sum(np.sin(a)) + tag

    @numba.njit(cache=False)
    def outer(a):
        s = 0.0
        for k in range(a.shape[0]):
            s += inner(a[k:])
        return s
    return outer


def test_a_compilation_is_counted_once_with_its_callees_inside():
    outer = _fresh_kernels(time.time())
    a = np.linspace(0.0, 1.0, 16)
    before = compile_seconds()
    t0 = time.perf_counter()
    outer(a)
    first = time.perf_counter() - t0
    counted = compile_seconds() - before
    # the first call is nearly all compilation (two kernels, the callee's inside the caller's
    # event: counted twice it would exceed the call's own wall time)
    assert 0.5 * first < counted <= first
    again = compile_seconds()
    outer(a)
    assert compile_seconds() == again


def test_a_run_reports_its_compile_seconds_within_its_total(femdem):
    """In process and with an engine's worker: a number within the total (the suite's kernels
    are cached, so most runs compile little; the bench's own test covers its use)."""
    for engine in ("liggghts", "lammps"):
        code, s, err = femdem("run", "coupled_free_flight", "--dem", engine)
        assert code == 0, err
        t = s["timing_s"]
        assert 0.0 <= t["compile"] <= t["total"], t


@pytest.mark.slow
def test_an_engine_worker_s_compilation_is_reported(femdem, monkeypatch, tmp_path):
    """The LAMMPS worker hosting the ply bonds compiles them into an empty cache (a few
    seconds) and loads them the second time: the run's compile seconds say which."""
    monkeypatch.setenv("FEMDEM_CACHE_DIR", str(tmp_path / "cache"))  # the worker's kernels only
    seconds = []
    for _ in range(2):
        code, s, err = femdem("run", "ply_fracture", "--dem", "lammps")
        assert code == 0, err
        seconds.append(s["timing_s"]["compile"])
    assert seconds[0] > 1.0 and seconds[1] < 0.1 * seconds[0], seconds
