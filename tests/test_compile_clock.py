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
    for engine, ranks in (("liggghts", 1), ("lammps", 1), ("lammps", 2)):  # (two ranks: the longest)
        code, s, err = femdem("run", "coupled_free_flight", "--dem", engine, "--set", f"dem.ranks={ranks}")
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


@pytest.mark.parametrize("conversion", ["rebuild", "release"])
def test_a_zone_grown_on_an_engine_worker_books_its_compile_seconds(femdem, conversion):
    """A rebuilt zone's old model is closed (its worker finalized) before the clock books its
    time, and a released zone's models share one worker: the run still ends ok, its worker's
    compile seconds read once (after finalize, from the reading kept) and within the total."""
    from test_growth import GROW, _sets
    code, s, err = femdem("run", "beam_impact_coarse", "--dem", "lammps",
                          *_sets(dict(GROW, **{"clock.t_end": 9e-6, "zone.conversion": conversion})))
    assert code == 0 and s["status"] == "ok", (err, s and s["message"])
    assert s["qoi"]["zone_conversions"] >= 1
    assert 0.0 <= s["timing_s"]["compile"] <= s["timing_s"]["total"]


def test_a_worker_s_compile_seconds_are_booked_once():
    """RemoteBackend.compile_seconds gives what the worker compiled since the last call, and
    after finalize what its last reading added (the worker's own clock only grows)."""
    from dem_region.backends.remote import RemoteBackend
    readings = iter([5.0, 5.0, 7.5])

    class Conn:
        closed = False
    be = object.__new__(RemoteBackend)
    be.conn, be._compiled, be._compiled_booked = Conn(), 0.0, 0.0
    be._call = lambda *msg: ("ok", next(readings))
    assert [be.compile_seconds(), be.compile_seconds(), be.compile_seconds()] == [5.0, 0.0, 2.5]
    be._compiled = 9.0  # finalize's last reading, then the connection closed
    be.conn.closed = True
    assert [be.compile_seconds(), be.compile_seconds()] == [1.5, 0.0]


def test_an_interactive_run_says_once_that_it_compiles():
    """The announcement runs before the next compilation only, once for a kernel and its
    callee, and not again for later ones."""
    from physics.compile_clock import announce_once
    said = []
    announce_once(lambda: said.append(1))
    a = np.linspace(0.0, 1.0, 8)
    _fresh_kernels(time.time())(a)
    _fresh_kernels(time.time() + 1.0)(a)
    assert said == [1]


def test_execute_announces_compiling_only_on_a_terminal_without_quiet(monkeypatch, tmp_path, capsys):
    """Set for an interactive run (a terminal, not --quiet), cleared at its end; a quiet or
    piped run sets nothing."""
    import sys

    from coupling.case import load_case
    from coupling.run import execute
    from physics import compile_clock
    seen = []
    monkeypatch.setattr(compile_clock, "announce_once", lambda say: seen.append(say is not None))
    for k, (tty, quiet) in enumerate([(False, False), (True, True), (True, False)]):
        monkeypatch.setattr(sys.stderr, "isatty", lambda: tty, raising=False)
        code, _, s = execute(load_case("chain_consistency"), "fem", "liggghts", tmp_path / f"r{k}", quiet)
        assert code == 0 and s["status"] == "ok", s["message"]
    assert seen == [False, False, True, False]  # (each run's end clears it)
