"""Coupled FEM + DEM (YADE) runs and the transition-interface maps."""
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from conftest import assert_checks
from fem_region import materials
from fem_region.elements import ELEMENTS
from fem_region.region import FemRegion
from interfaces.transition import InterfaceError, TransitionInterface


@pytest.mark.parametrize("sets", [[], ["chain.fem_elements=7", "chain.particles=13", "material.E=2e9",
                                       "zone.particle_size=0.004"]])
def test_chain_consistency_matches_monolithic(femdem, sets):
    code, s, _ = femdem("run", "chain_consistency", *sum((["--set", x] for x in sets), []))
    assert code == 0
    assert_checks(s)
    assert s["counts"]["interface_particles"] == 1
    assert s["qoi"]["max_displacement"] > 0  # the pulse really crossed into the DEM part
    assert s["energy"]["balance_error_rel"] < 0.02
    assert set(s["timing_s"]) >= {"fem", "dem", "interface", "io", "orchestrator", "total"}
    assert s["memory_peak_mb"]["orchestrator"] > 10  # the interpreter alone takes more


@pytest.mark.parametrize("mode", ["coupled", "fem", "dem"])
def test_summary_lists_the_steps_stages_in_order_and_they_make_the_buckets(femdem, mode):
    """summary.json "stages": the clock step's named stages in running order (a coupled step:
    the engine's step with laws, interface.read, fem.forces, fem.kick_drift, interface.write
    inside its hook); each bucket of timing_s is at least the sum of its stages' times."""
    code, s, err = femdem("run", "beam_impact_coarse", "--mode", mode, "--set=clock.t_end=2e-5")
    assert code == 0, err
    names = [st["name"] for st in s["stages"]]
    if mode == "coupled":
        assert names[0].startswith("engine.step x ")
        assert names[1:] == ["laws", "interface.read", "fem.forces", "fem.kick_drift", "interface.write"]
        assert all(st.get("within") == names[0] for st in s["stages"][1:])
    elif mode == "fem":
        assert names == ["fem.kick_drift", "fem.forces", "fem.kick"]
    else:
        assert names == ["engine.step", "laws"]
    for timer in {st["timer"] for st in s["stages"]}:
        staged = sum(st["s"] for st in s["stages"] if st["timer"] == timer)
        assert s["timing_s"][timer] >= staged - s["timing_s"].get("transport", 0.0) - 1e-9
    assert all(st["s"] >= 0 for st in s["stages"])


def test_engine_without_its_environment_is_refused_clearly(femdem, monkeypatch):
    """A worker engine whose environment is missing: one line with the fix, exit 2."""
    from pathlib import Path
    import dem_region.backends as backends
    monkeypatch.setitem(backends.WORKER_ONLY, "lammps", Path("/nonexistent/venv/bin/python"))
    code, s, err = femdem("run", "chain_consistency", "--dem", "lammps")
    assert code == 2 and s is None
    assert "lammps" in err and "setup.sh" in err and len(err.strip().splitlines()) == 1


def _region(kind, nx, ny, jitter, seed):
    rng = np.random.default_rng(seed)
    m = ELEMENTS[kind].mesh_cls.init_tensor(np.linspace(0, 1, nx + 1), np.linspace(0, 1, ny + 1))
    p = m.p.copy()
    inner = (p[0] > 0) & (p[0] < 1) & (p[1] > 0) & (p[1] < 1)
    p[:, inner] += jitter / max(nx, ny) * rng.uniform(-1, 1, (2, inner.sum()))
    m = type(m)(p, m.t)
    return FemRegion(m, ELEMENTS[kind], materials.plane_strain(materials.isotropic(1e9, 0.3)), 1000.0, 1.0)


@settings(max_examples=25, deadline=None, derandomize=True)
@given(kind=st.sampled_from(["quad4", "tri3"]), nx=st.integers(1, 6), ny=st.integers(1, 6),
       jitter=st.floats(0, 0.3), n=st.integers(1, 40), seed=st.integers(0, 2**31))
def test_interface_maps(kind, nx, ny, jitter, n, seed):
    """Weights sum to one, linear fields are reproduced, forces map by the transpose
    (equal virtual work) and total force (momentum rate) is conserved."""
    rng = np.random.default_rng(seed)
    r = _region(kind, nx, ny, jitter, seed)
    x = np.zeros((n, 3))
    x[:, :2] = rng.uniform(0.02, 0.98, (n, 2))
    itf = TransitionInterface.build(r, x, np.arange(n))
    assert np.allclose(itf.W.sum(axis=1), 1.0, atol=1e-12)
    G = rng.normal(size=(2, 2))
    assert np.allclose(itf.to_particles(r.X @ G.T)[:, :2], x[:, :2] @ G.T, atol=1e-10)
    F = rng.normal(size=(n, 3))
    v = rng.normal(size=(r.n_nodes, 2))
    assert np.isclose(np.vdot(itf.to_nodes(F), v), np.vdot(F, itf.to_particles(v)), rtol=1e-10, atol=1e-12)
    assert np.allclose(itf.to_nodes(F).sum(axis=0), F[:, :2].sum(axis=0), atol=1e-10)
    m = rng.uniform(0.1, 1.0, n)
    assert itf.share_mass(m).sum() == pytest.approx(m.sum(), rel=1e-12)


def test_interface_particle_outside_mesh_is_refused():
    r = _region("quad4", 2, 2, 0.0, 0)
    x = np.array([[0.5, 0.5, 0.0], [1.5, 0.5, 0.0]])
    with pytest.raises(InterfaceError):
        TransitionInterface.build(r, x, np.arange(2))
    with pytest.raises(InterfaceError):
        TransitionInterface.build(r, x, np.zeros(0, int))


@pytest.mark.parametrize("eps", [1e-15, 1e-12])
def test_a_particle_on_the_edge_of_a_hole_is_hosted(eps):
    """A particle on the edge of a hole in the FEM (a DEM window's), outside it by round-off,
    whose nearest element centre lies across the hole: hosted by the element it touches, with
    the weights that reproduce its position (the panel's 3-ply window edge was refused)."""
    from fem_region import mesh
    m = mesh.cut_rectangle([0, 1, 2], [0, 0.1, 1.1], lambda cx, cy: not (cx < 1 and cy > 0.1))
    r = FemRegion(m, ELEMENTS["quad4"], materials.plane_strain(materials.isotropic(1e9, 0.3)), 1000.0, 1.0)
    x = np.array([[1 - eps, 0.2, 0.0]])
    itf = TransitionInterface.build(r, x, np.arange(1))
    assert itf.to_particles(r.X)[0, :2] == pytest.approx([1.0, 0.2], abs=1e-8)


@settings(max_examples=15, deadline=None, derandomize=True)
@given(n_in=st.integers(0, 30), n_edge=st.integers(1, 6), eps=st.sampled_from([0.0, 1e-15, 1e-12]),
       seed=st.integers(0, 2**31))
def test_particles_on_the_hole_s_edge_among_others_are_hosted_as_one_by_one(n_in, n_edge, eps, seed):
    """Particles inside the mesh mixed with ones on the edge of its hole (outside by round-off,
    which the element finder rejects): the weights of the whole set equal those of each
    particle hosted on its own, row for row (only the rejected ones are hosted one by one)."""
    from fem_region import mesh
    rng = np.random.default_rng(seed)
    m = mesh.cut_rectangle([0, 0.5, 1, 1.5, 2], [0, 0.1, 0.6, 1.1], lambda cx, cy: not (cx < 1 and cy > 0.1))
    r = FemRegion(m, ELEMENTS["quad4"], materials.plane_strain(materials.isotropic(1e9, 0.3)), 1000.0, 1.0)
    inside = np.column_stack([rng.uniform(1.02, 1.98, n_in), rng.uniform(0.02, 1.08, n_in), np.zeros(n_in)])
    edge = np.column_stack([np.full(n_edge, 1 - eps), rng.uniform(0.15, 1.05, n_edge), np.zeros(n_edge)])
    x = rng.permutation(np.vstack([inside, edge]))
    W = TransitionInterface.build(r, x, np.arange(len(x))).W.toarray()
    for i in range(len(x)):
        one = TransitionInterface.build(r, x[i:i + 1], np.arange(1)).W.toarray()[0]
        np.testing.assert_allclose(W[i], one, rtol=0, atol=1e-12)
    assert np.allclose(W @ r.X, x[:, :2], atol=1e-8)


def test_coupled_free_flight_momentum(femdem):
    code, s, _ = femdem("run", "coupled_free_flight")
    assert code == 0
    assert_checks(s)
    assert s["counts"]["interface_particles"] > 5 and s["energy"]["balance_error_rel"] < 0.01


@pytest.mark.parametrize("m", [2, 5, 10])
def test_subcycled_coupling_is_stable_and_conserves_momentum(femdem, m):
    """Impulse multiple time stepping: exact momentum up to the round-off of the larger slow
    kicks (a few 1e-12 with m = 5 over 400 FEM steps), energy bounded (no drift)."""
    code, s, _ = femdem("run", "coupled_free_flight", "--set", f"clock.substeps={m}", "--set", "run.steps=600")
    assert code == 0
    assert s["clock"]["substeps"] == m and s["clock"]["dt_dem"] == pytest.approx(s["clock"]["dt_fem"] / m)
    assert s["qoi"]["momentum_drift_rel"] < 1e-11
    assert s["energy"]["balance_error_rel"] < 0.01


def test_worker_process_gives_the_same_numbers(femdem, tmp_path):
    """The same case with the engine in a worker process (shared memory + socket) reproduces
    the in-process run bit for bit, and leaves no process or shared-memory block behind (its
    own: the blocks this process makes carry its PID; other tests run beside it)."""
    import glob
    import os
    import subprocess
    import h5py
    ours = f"/dev/shm/femdem_{os.getpid()}_*"
    shm_before = set(glob.glob(ours))
    code_a, a, _ = femdem("run", "chain_consistency")
    code_b, b, _ = femdem("run", "chain_consistency", "--set", "dem.process=worker")
    assert code_a == code_b == 0 and b["parameters"]["dem.process"] == "worker"
    assert a["qoi"] == b["qoi"]
    ha = h5py.File(tmp_path / "run0" / "history.h5")["history"]
    hb = h5py.File(tmp_path / "run1" / "history.h5")["history"]
    for k in ha:
        if k.startswith("u_"):
            assert np.array_equal(ha[k][:], hb[k][:]), k
    assert set(glob.glob(ours)) <= shm_before
    ps = subprocess.run(["pgrep", "-P", str(os.getpid()), "-f", "dem_region.worker"], capture_output=True, text=True)
    assert ps.stdout.strip() == ""


def test_interface_patch_uniform_strain(femdem):
    """Uniform strain across the tie: free particles balance to round-off, and the interface
    residual is the bonds' geometric nonlinearity: it scales linearly with the strain."""
    res = []
    for e in (1e-4, 1e-5):
        code, s, _ = femdem("run", "interface_patch", "--set", f"strain.xx={e}", "--set", f"strain.yy={-0.3 * e}",
                            "--set", f"strain.xy={0.5 * e}", "--set", "mesh.spacing_ratio=2")
        assert code == 0
        assert_checks(s)
        assert s["qoi"]["interface_force_rel"] == pytest.approx(1.0, rel=1e-3)  # the tie carries the stress
        res.append(s["qoi"]["max_interface_residual_rel"])
    assert res[1] / res[0] == pytest.approx(0.1, rel=0.05)


@pytest.mark.parametrize("m", [1, 5])
def test_interface_wave_transmission(femdem, m):
    code, s, _ = femdem("run", "interface_wave", "--set", f"clock.substeps={m}")
    assert code == 0
    assert_checks(s)
    assert s["clock"]["substeps"] == m
    q = s["qoi"]
    assert q["reflected_energy_fraction"] + q["transmitted_energy_fraction"] == pytest.approx(1.0, abs=0.01)


@pytest.mark.parametrize("m", [1, 5])
def test_coupled_vibration_energy_short(femdem, m):
    """5,000 FEM steps of the undamped coupled cantilever (the 10^5-step study is marked slow)."""
    code, s, _ = femdem("run", "coupled_vibration", "--set", f"clock.substeps={m}", "--set", "run.steps=5000")
    assert code == 0
    assert_checks(s)
    assert s["qoi"]["tip_amplitude"] > 1e-5  # it really vibrates


@pytest.mark.slow
@pytest.mark.parametrize("m", [1, 2, 5, 10])
def test_coupled_vibration_energy_1e5_steps(femdem, m):
    code, s, _ = femdem("run", "coupled_vibration", "--set", f"clock.substeps={m}")
    assert code == 0 and s["clock"]["steps"] == 100_000
    assert_checks(s)


def test_penalty_tie_converges_to_the_kinematic_tie(femdem):
    """The seed paper's penalty transition contact: as the tie stiffness grows the coupled
    chain approaches the monolithic chain (the kinematic tie is its rigid limit); energy,
    including the springs' store, is conserved."""
    errs = []
    for k in (2e7, 2e8, 2e9):
        code, s, _ = femdem("run", "chain_consistency", "--set", "coupling.tie=penalty", "--set", f"coupling.tie_penalty={k}",
                            "--set", "clock.substeps=1")  # the tie alone, no subcycling error
        assert code == 0 and s["status"] == "ok"
        assert s["energy"]["balance_error_rel"] < 0.01
        errs.append(s["qoi"]["max_rel_diff_vs_monolithic"])
    assert errs[0] > errs[1] > errs[2]
    assert errs[2] < 0.1 * errs[0]


def test_a_penalty_tie_through_an_engine_s_worker_equals_the_in_process_one():
    """The penalty tie reads its particles and writes their forces through the worker's shared
    block (LIGGGHTS in a worker: the models hosted there, one rank) where it sent a message each
    step: it takes the block, and every history series is the same to the bit as the engine's
    in process."""
    from coupling.case import load_case
    from coupling.simulation import run_clock
    runs = []
    for process in ("in-process", "worker"):
        case = load_case("beam_impact_coarse", {"coupling.tie": "penalty", "dem.process": process,
                                                "clock.t_end": 3e-5})
        sim = case.scene.build(case.parameters, "coupled", "liggghts")
        clock = sim.stages[0].run.__self__  # (the coupled clock whose step the stage runs)
        try:
            runs.append(run_clock(sim)["history"])
            if process == "worker":
                assert clock.dem._model_ids is clock.tie.itf.ids  # the tie's particles in the shared block
        finally:
            sim.close()
    assert runs[0].keys() == runs[1].keys()
    for k in runs[0]:
        assert np.array_equal(runs[0][k], runs[1][k], equal_nan=True), k


def test_stiff_penalty_tie_subcycled_does_not_resonate(femdem):
    """Hard case: a stiff penalty tie with 4 and 8 substeps (it resonated at m = 4 while the
    interface band's elements were slow forces) stays within 1 % of energy and of the
    monolithic chain, and the automatic count subcycles it too."""
    for m in (4, 8, 0):
        code, s, _ = femdem("run", "chain_consistency", "--set", "coupling.tie=penalty",
                            "--set", "coupling.tie_penalty=2e8", "--set", f"clock.substeps={m}")
        assert code == 0, s["message"]
        assert s["energy"]["balance_error_rel"] < 0.01 and s["qoi"]["max_rel_diff_vs_monolithic"] < 0.01
    c = s["clock"]  # the most DEM steps that fit in a FEM step (to round-off: 1e-5 / 2e-6 is 5)
    m, fem, dem = c["substeps"], c["dt_stable_fem"], c["dt_stable_dem"]
    assert m > 1 and m * dem <= fem * (1 + 1e-12) and (m + 1) * dem > fem


def test_energy_guard_stops_a_subcycled_run_with_a_diagnostic(femdem):
    """The guard, the last line of defence: a subcycled run whose energy balance leaves its
    tolerance stops with exit code 3, says why and what to try (on stderr, where a caller
    looks), and still publishes its run directory with status 'unstable'."""
    code, s, err = femdem("run", "chain_consistency", "--set", "clock.substeps=4", "--set", "guards.energy_growth=1e-9")
    assert code == 3 and s["status"] == "unstable"
    assert s["message"] in err and "unstable" in err.splitlines()[0]
    assert "energy balance error" in s["message"] and "clock.substeps" in s["message"]
    assert s["clock"]["steps"] < 200  # stopped early, not after producing garbage


def test_coupled_against_standalone_modes(femdem):
    """The same chain coupled, all-FEM and all-DEM: each matches its own monolithic chain to
    round-off, and the three tip histories differ only by their mass distributions (< 0.5 %)."""
    tips = {}
    for mode in ("coupled", "fem", "dem"):
        code, s, _ = femdem("run", "chain_consistency", "--mode", mode)
        assert code == 0 and s["mode"] == mode
        assert_checks(s)
        tips[mode] = s["qoi"]["tip_displacement_max"]
    assert max(tips.values()) / min(tips.values()) - 1 < 5e-3


def test_bench_speed_against_error(tmp_path, monkeypatch, capsys):
    """femdem bench: the reference is run once and then cached; errors are relative to it."""
    import json
    from coupling.cli import main
    monkeypatch.setenv("FEMDEM_CACHE_DIR", str(tmp_path / "cache"))
    args = ["bench", "chain_consistency", "--sweep", "clock.substeps=1,2", "--qoi", "tip_displacement_max",
            "--dem", "yade"]  # (the last --dem given wins: b3 names two engines)
    assert main(args + ["--out", str(tmp_path / "b1")]) == 0
    r = json.loads((tmp_path / "b1" / "speed_error.json").read_text())
    assert not r["reference"]["cached"] and len(r["points"]) == 2
    assert all(p["status"] == "ok" and 0 < p["max_rel_error"] < 5e-3 for p in r["points"])
    assert any(p.get("pareto") for p in r["points"]) and (tmp_path / "b1" / "speed_error.png").exists()
    assert main(args + ["--out", str(tmp_path / "b2")]) == 0
    assert json.loads((tmp_path / "b2" / "speed_error.json").read_text())["reference"]["cached"]
    # the engine as an axis: one curve per engine, the reference on the first
    assert main(args + ["--dem", "yade,liggghts", "--out", str(tmp_path / "b3")]) == 0
    r = json.loads((tmp_path / "b3" / "speed_error.json").read_text())
    assert r["reference"]["cached"] and [p["dem"] for p in r["points"]] == ["yade", "yade", "liggghts", "liggghts"]
    assert all(p["status"] == "ok" and 0 < p["max_rel_error"] < 5e-3 for p in r["points"])
    assert main(["bench", "chain_consistency", "--dem", "yade,fluent", "--out", str(tmp_path / "b4")]) == 2


def test_a_repeated_bench_runs_its_reference_beside_its_points_and_reports_medians(tmp_path, monkeypatch, capsys):
    """--repeat N: N rounds of the reference (run again, though cached) and every point, each
    run in its own directory; each point's wall time is the median of its runs and its speedup
    the median of the rounds' ratios of the reference's wall time to its own, its errors those
    of a single bench (the runs repeat to the bit). A --repeat outside 1-20 is refused in one
    line before anything is written."""
    import json
    import statistics
    from coupling.cli import main
    monkeypatch.setenv("FEMDEM_CACHE_DIR", str(tmp_path / "cache"))
    args = ["bench", "chain_consistency", "--sweep", "clock.substeps=2", "--qoi", "tip_displacement_max"]
    assert main(args + ["--out", str(tmp_path / "once")]) == 0
    once = json.loads((tmp_path / "once" / "speed_error.json").read_text())
    capsys.readouterr()
    assert main(args + ["--repeat", "3", "--out", str(tmp_path / "b")]) == 0
    assert "3 runs, median" in capsys.readouterr().out
    r = json.loads((tmp_path / "b" / "speed_error.json").read_text())
    ref = r["reference"]
    assert not ref["cached"] and len(ref["wall_s_runs"]) == 3 and ref["wall_s"] == statistics.median(ref["wall_s_runs"])
    assert all((tmp_path / "b" / name).is_dir() for name in ("reference-r1", "reference-r2", "reference-r3",
                                                             "substeps2-r1", "substeps2-r2", "substeps2-r3"))
    (p,) = r["points"]
    assert p["status"] == "ok" and p["repeatable"] and len(p["wall_s_runs"]) == 3
    assert p["wall_s"] == statistics.median(p["wall_s_runs"])
    assert p["speedup"] == statistics.median(a / b for a, b in zip(ref["wall_s_runs"], p["wall_s_runs"]))
    assert p["rel_error"] == once["points"][0]["rel_error"] and p["qoi"] == once["points"][0]["qoi"]
    # a single bench's speedup is against its one reference run (here from the cache)
    assert once["points"][0]["speedup"] == once["reference"]["wall_s"] / once["points"][0]["wall_s"]
    for bad in ("0", "21"):
        assert main(args + ["--repeat", bad, "--out", str(tmp_path / "bad")]) == 2
        err = capsys.readouterr().err.strip()
        assert err.count("\n") == 0 and f"--repeat {bad}" in err and "allowed" in err
        assert not (tmp_path / "bad").exists()
    # a key unknown to the case is named with the option that gave it
    for option in ("--sweep", "--set", "--reference-set"):
        value = "clock.nope=1,2" if option == "--sweep" else "clock.nope=1"
        assert main(["bench", "chain_consistency", option, value, "--out", str(tmp_path / "bad")]) == 2
        err = capsys.readouterr().err.strip()
        assert err.count("\n") == 0 and f"clock.nope: unknown key in {option};" in err, err
        assert not (tmp_path / "bad").exists()


def test_a_bench_compares_the_structure_not_the_zone_s_own_diagnostics():
    """By default a bench compares every qoi both runs report but error measures, the model's
    size and the zone-edge probe's (an all-DEM reference reads the damage where the zone would
    end: beam_impact's 0.79, which made every coupled point's error 100 %)."""
    from coupling.bench import compared_qoi
    from coupling.case import load_case
    p = load_case("beam_impact_coarse").parameters
    edge = [k.split(".")[1] for k, v in p.items() if k.endswith(".kind") and v == "zone_edge_damage"]
    assert edge
    run = {"peak_contact_force": 1.0, edge[0]: 0.0, "model_size": 9.0, "balance_error_rel": 1e-5, "zone_half_width": 1.0}
    ref = {"peak_contact_force": 1.1, edge[0]: 0.8, "model_size": 90.0, "balance_error_rel": 1e-6}
    assert compared_qoi(p, run, ref) == ["peak_contact_force"]
