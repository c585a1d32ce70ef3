"""The fused law kernels (dem_region/law_kernels.py) against the readable reference
(LawBonds.apply_reference: the law's vectorised equations, friction_traction, the numpy
scatter) on random deformation paths from elastic through softening to fully failed faces
sliding with friction, for every law family the scenes build: forces, separations, tractions,
damage, failure times and the law's state agree bit for bit (the incidence lists follow the
reference's order of sums); the dissipated work to round-off (its sum runs in another order).
"""
from __future__ import annotations

import copy
from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest
from hypothesis import example, given, settings, strategies as st

from physics.law_bonds import LawBonds
from physics.laws import HashinCohesiveLaw

ROOT = Path(__file__).resolve().parents[1]
AS4 = HashinCohesiveLaw(K=1e14, Z0=80e6, R0=100e6, GIc=969.0, GIIc=1719.0, eta=2.284)


class _Arrays:
    """A particle array target (what ModelStep is): rows = particle ids."""

    def __init__(self, x):
        self.x, self.f = x, np.zeros_like(x)

    def rows_of(self, ids):
        return ids


class _Engine:
    """A target without arrays: positions_of / add_forces only (the copy path)."""

    def __init__(self, x):
        self.x, self.f = x, np.zeros_like(x)

    def positions_of(self, ids):
        return self.x[ids]

    def add_forces(self, ids, F):
        np.add.at(self.f, ids, F)


@lru_cache(maxsize=None)
def _family(name: str):
    """(LawBonds, reference positions X (n, 3), plane) of one law family as a scene builds it."""
    from coupling.case import load_case
    if name in ("ply_2d", "interface_2d"):
        from coupling.study.assemble import particle_zone
        out = particle_zone(load_case("beam_impact_coarse").parameters, 3e-3, tied=False, clamped=True)
        return (out[2] if name == "ply_2d" else out[3]), out[0].x, True
    if name in ("ply_3d", "interface_3d"):
        from coupling.study.assemble import particle_zone
        out = particle_zone(load_case("beam_impact_3d_coarse").parameters, 2.4e-3, tied=False, clamped=True)
        return (out[2] if name == "ply_3d" else out[3]), out[0].x, False
    n, h = 8, 1e-3
    X = np.array([[c * h, y, 0.0] for c in range(n) for y in (0.0, h)])
    pairs = np.arange(2 * n).reshape(n, 2)
    k = np.arange(n)
    along = np.column_stack([np.where(k > 0, k - 1, -1), np.where(k < n - 1, k + 1, -1)])
    if name == "corotated_interface":
        return LawBonds(pairs, X, [[0.0, 1.0, 0.0]] * n, h * h, AS4, along=along, finite_rotation=True,
                        friction=0.4), X, True
    if name == "central_hashin":  # node pairs (rod_impact's FEM layers): raw relative translation
        return LawBonds(pairs, X, [[0.0, 1.0, 0.0]] * n, h * h, AS4, friction=0.3), X, True
    if name in ("corotated_ply", "lattice_springs"):  # springs: a window's lattice (no strength: never fails)
        from physics.laws import PlyBondLaw
        from physics.failure import HoffmanStrengths
        X = np.array([[i * h, j * h, 0.0] for i in range(4) for j in range(4)])
        pairs = np.array([(a, b) for a in range(16) for b in range(a + 1, 16) if np.linalg.norm(X[a] - X[b]) < 1.5 * h])
        strength = np.inf if name == "lattice_springs" else 60e6
        law = PlyBondLaw(np.full(len(pairs), 1e14), [[100.0, 50.0]], HoffmanStrengths(*([strength] * 9)), np.eye(3))
        return LawBonds(pairs, X, X[pairs[:, 1]] - X[pairs[:, 0]], h * h, law, volume=np.full(16, h**3),
                        finite_rotation=True, friction=0.2), X, True
    raise KeyError(name)


FAMILIES = ["ply_2d", "interface_2d", "ply_3d", "interface_3d", "corotated_interface", "central_hashin",
            "corotated_ply", "lattice_springs"]


@pytest.mark.parametrize("name", FAMILIES)
@settings(max_examples=6, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**31), strain=st.floats(1e-4, 0.3), spin=st.floats(-0.3, 0.3),
       noise=st.floats(0.0, 3e-3), dt=st.sampled_from([0.0, 1e-9, 3e-8]))
@example(seed=1, strain=0.3, spin=0.2, noise=1e-3, dt=1e-9)  # every bond fails, closed faces slide
def test_fused_kernels_are_the_reference_law(name, seed, strain, spin, noise, dt):
    """A path of 60 steps: stretch and shear growing to ``strain`` (above 0.1 most bonds fail,
    at 0.3 nearly all), then pressed back past closing (closed failed faces slide with friction), with
    a rigid spin (large for the corotated families) and random noise of ``noise`` x the spacing."""
    bonds0, X, plane = _family(name)
    fused, ref = copy.deepcopy(bonds0), copy.deepcopy(bonds0)
    rng = np.random.default_rng(seed)
    sliding = 0  # most failed bonds closed at once
    h = float(np.median(np.linalg.norm(fused.d0, axis=1)))
    corotated = fused.finite_rotation
    for k in range(60):
        s = strain * (k / 40 if k < 40 else (60 - k) / 20 - 0.5)  # load, then press back past closing
        e = np.array([[s, 0.6 * s, 0.0], [0.4 * s, s, 0.0], [0.3 * s, 0.2 * s, s]])
        x = X + (X - X.mean(axis=0)) @ e.T + rng.normal(size=X.shape) * noise * h
        if corotated:
            c, sn = np.cos(spin * k / 60), np.sin(spin * k / 60)
            x = x @ np.array([[c, -sn, 0], [sn, c, 0], [0, 0, 1]]).T
        if plane:
            x[:, 2] = X[:, 2]
        a, b = _Arrays(x.copy()), _Engine(x.copy())
        fused.apply(a, dt)
        ref.apply_reference(b, dt)
        np.testing.assert_array_equal(a.f, b.f)
        sliding = max(sliding, int(np.sum((ref.damage >= 1) & (np.einsum("bi,bi->b", ref.delta, ref.normal) < 0))))
    if name == "lattice_springs":  # the fused step's elastic path (no stress, no index), the reference's Hoffman
        from physics import law_kernels
        assert fused._plan.law == law_kernels.ELASTIC and not ref.failed().any()
    elif strain >= 0.3:  # the path is not vacuous: (nearly) every bond failed, closed faces slid
        assert ref.failed().mean() > 0.9 and sliding > 0
    for key in ("damage", "delta", "traction", "t_failed"):
        np.testing.assert_array_equal(getattr(fused, key), getattr(ref, key))
    for key in ("m0", "mf", "crushed", "snapback"):
        if hasattr(fused.law, key):
            np.testing.assert_array_equal(getattr(fused.law, key), getattr(ref.law, key))
    assert fused.work == pytest.approx(ref.work, rel=1e-12, abs=1e-12 * (abs(ref.work) + 1e-30))
    # the friction's share of it (the tangential tractions of failed bonds), in both
    assert fused.friction_work == pytest.approx(ref.friction_work, rel=1e-9, abs=1e-12 * (abs(ref.work) + 1e-30))
    assert ref.friction_work >= -1e-9 * abs(ref.work)  # friction takes energy, never gives it


def _path(X, plane, seed, steps, strain=0.3):
    """Positions of ``steps`` steps loading a family to ``strain`` (most bonds softened or
    failed), with noise: (steps, n, 3) m."""
    rng = np.random.default_rng(seed)
    h = float(np.median(np.linalg.norm(X[1:] - X[:-1], axis=1)))
    out = []
    for k in range(steps):
        s = strain * (k + 1) / steps
        e = np.array([[s, 0.6 * s, 0.0], [0.4 * s, s, 0.0], [0.3 * s, 0.2 * s, s]])
        x = X + (X - X.mean(axis=0)) @ e.T + rng.normal(size=X.shape) * 1e-3 * h
        if plane:
            x[:, 2] = X[:, 2]
        out.append(x)
    return out


@pytest.mark.parametrize("name", FAMILIES)
@pytest.mark.parametrize("passes", ["plan", "arguments"])
@settings(max_examples=3, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**31), before=st.integers(5, 25), after=st.integers(5, 25))
def test_the_compiled_plan_follows_replaced_arrays(name, passes, seed, before, after):
    """A family's step runs on arguments bound once (a small family's: one compiled plan holding
    its arrays; a large one's, or one whose ranks exchange between the passes: argument tuples);
    a restore (a checkpoint, a grown zone's carried state) and the numpy reference replace
    them. A family that ran another path, then restored, goes on as the family it was restored
    from, to the bit; a family stepped by the reference and the fused step in turn is the
    reference. ``passes``: the plan, or the tuples (a no-op between the passes takes them)."""
    bonds0, X, plane = _family(name)
    between = None if passes == "plan" else (lambda bonds: None)
    step = lambda bonds, target: bonds.apply(target, 1e-9, between_passes=between)
    path = _path(X, plane, seed, before + after)
    a, b = copy.deepcopy(bonds0), copy.deepcopy(bonds0)
    for x in path[:before]:
        step(a, _Arrays(x.copy()))
    state = copy.deepcopy(a.checkpoint_state())
    for x in _path(X, plane, seed + 1, before):  # b: bound to its arrays by another path
        step(b, _Arrays(x.copy()))
    b.restore_state(state)
    for x in path[before:]:
        ta, tb = _Arrays(x.copy()), _Arrays(x.copy())
        step(a, ta)
        step(b, tb)
        np.testing.assert_array_equal(ta.f, tb.f)
    np.testing.assert_array_equal(a.damage, b.damage)
    assert a.damage.any() or name == "lattice_springs"  # (not vacuous: the path softened bonds; springs never do)
    mixed, ref = copy.deepcopy(bonds0), copy.deepcopy(bonds0)
    for k, x in enumerate(path):
        tm, tr = _Arrays(x.copy()), _Engine(x.copy())
        (step(mixed, tm) if k % 2 else mixed.apply_reference(_Engine(tm.x), 1e-9))
        ref.apply_reference(tr, 1e-9)
        if k % 2:
            np.testing.assert_array_equal(tm.f, tr.f)
    for key in ("damage", "delta", "traction", "t_failed"):
        np.testing.assert_array_equal(getattr(mixed, key), getattr(ref, key))


@pytest.mark.parametrize("name", FAMILIES)
@settings(max_examples=4, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**31), steps=st.integers(1, 30), strain=st.floats(1e-4, 0.3))
def test_compiled_stored_energy_is_the_laws_density(name, seed, steps, strain):
    """LawBonds.stored_energy (compiled) = the area-weighted sum of the law's stored_density
    (numpy) at the state a loading path leaves (elastic, softened, failed and closed bonds), to
    round-off; and it is the energy the tractions store: 0 at rest."""
    bonds0, X, plane = _family(name)
    b = copy.deepcopy(bonds0)
    assert b.stored_energy() == 0.0
    for x in _path(X, plane, seed, steps, strain):
        b.apply(_Arrays(x.copy()), 1e-9)
    dn, ds = b.split(b.delta)
    ref = float(b.area @ b.law.stored_density(dn, ds, b.damage))
    assert ref > 0 or (b.damage >= 1).all()  # (zero only where every bond failed open)
    assert b.stored_energy() == pytest.approx(ref, rel=1e-12)


def test_the_copy_path_is_the_array_path():
    """A target without particle arrays (positions_of / add_forces) gets the same forces."""
    bonds0, X, _ = _family("interface_2d")
    a_, b_ = copy.deepcopy(bonds0), copy.deepcopy(bonds0)
    x = X + np.random.default_rng(0).normal(size=X.shape) * 1e-6 * [1, 1, 0]
    a, b = _Arrays(x.copy()), _Engine(x.copy())
    a_.apply(a, 1e-9)
    b_.apply(b, 1e-9)
    np.testing.assert_array_equal(a.f, b.f)


def test_large_families_run_in_parallel_to_the_same_bits():
    """Above PARALLEL_BONDS the parallel build runs; its forces equal the serial build's."""
    from physics import law_kernels
    bonds0, X, _ = _family("ply_3d")
    x = X + np.random.default_rng(1).normal(size=X.shape) * 3e-6
    out = []
    for threshold in (0, 10**9):
        law_kernels.PARALLEL_BONDS, saved = threshold, law_kernels.PARALLEL_BONDS
        try:
            b = copy.deepcopy(bonds0)
            b._plan = None
            a = _Arrays(x.copy())
            b.apply(a, 1e-9)
            out.append(a.f)
        finally:
            law_kernels.PARALLEL_BONDS = saved
    np.testing.assert_array_equal(out[0], out[1])


def _unit(rng, dim):
    a = rng.normal(size=dim)
    return a / np.linalg.norm(a)


@settings(max_examples=30, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**31), dim=st.sampled_from([2, 3]), friction=st.sampled_from([0.0, 0.3]),
       shape=st.sampled_from(["sphere", "cylinder"]))
def test_compiled_ball_contact_is_the_gap_form(seed, dim, friction, shape):
    """RigidImpactor.forces of a ball or a cylinder (compiled) = the readable gap form: penalty x
    penetration along the normal, Coulomb friction against the regularised tangential slip, to
    the bit for a ball, to round-off for a 3D cylinder along an oblique axis (its axial part is a
    dot product numpy forms in another order); stored energy to round-off."""
    from physics.impactor import RigidImpactor
    rng = np.random.default_rng(seed)
    axis = _unit(rng, dim) if shape == "cylinder" and dim == 3 else None
    imp = RigidImpactor(shape, rng.normal(size=dim) * 0.1, 1.0, 1.0, rng.normal(size=dim), 1e6,
                        friction=friction, axis=axis)
    x, v = rng.normal(size=(300, dim)) * 0.8, rng.normal(size=(300, dim))
    f, stored = imp.forces(x, v)
    pen, n = imp.gap(x)
    fn = imp.penalty * pen
    ref = fn[:, None] * n
    if friction:
        vr = v - imp.v
        vt = vr - np.einsum("mi,mi->m", vr, n)[:, None] * n
        ref -= (friction * fn / np.sqrt(np.einsum("mi,mi->m", vt, vt) + imp.slip_velocity**2))[:, None] * vt
    assert (pen > 0).any() and (pen == 0).any()
    if axis is None:
        np.testing.assert_array_equal(f, ref)
    else:
        np.testing.assert_allclose(f, ref, rtol=1e-11, atol=1e-11 * np.abs(ref).max())
    assert stored == pytest.approx(0.5 * imp.penalty * float(pen @ pen), rel=1e-11)


@settings(max_examples=16, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**31), shape=st.sampled_from(["sphere", "cylinder", "rod", "flat_punch"]),
       friction=st.sampled_from([0.0, 0.2]), rounding=st.sampled_from([0.0, 0.15]))
def test_particle_impactor_compiled_pass_is_its_readable_path(seed, shape, friction, rounding):
    """A sphere, a cylinder (along an oblique axis) or a flat face (a rod's or a punch's, sharp
    or grown by a particle's radius) striking particles that move under it: the compiled pass on
    the engine's arrays gives the forces, the impactor's motion and its contact ledger of the
    path through copies (RigidImpactor.forces, its gap in numpy), to round-off, step after step."""
    from dem_region.particle_impactor import ParticleImpactor
    from physics.impactor import FLAT, RigidImpactor
    rng = np.random.default_rng(seed)
    n, dt = 400, 1e-6
    X0 = rng.uniform(-1.0, 1.0, size=(n, 3))
    V = rng.normal(size=(n, 3)) * 20.0
    axis = _unit(rng, 3) if shape != "sphere" else None
    centre, velocity = rng.normal(size=3) * 0.1, rng.normal(size=3) * 50.0
    flat = {"depth": 0.5, "rounding": rounding} if shape in FLAT else {}
    runs = []
    for target in (_Arrays, _Engine):  # the compiled pass, the copies
        imp = ParticleImpactor(RigidImpactor(shape, centre, 0.6, 0.5, velocity, 1e5, friction=friction, axis=axis,
                                             **flat), np.arange(0, n, 2), fixed=(False, True, False))
        steps = []
        for k in range(30):
            eng = target(X0 + k * dt * V)
            imp.apply(eng, dt if k else 0.0)
            steps.append(eng.f)
        runs.append((imp, np.array(steps)))
    (a, fa), (b, fb) = runs
    assert np.abs(fb).max() > 0 and (fb == 0).any()  # it touched some, not all
    np.testing.assert_allclose(fa, fb, rtol=1e-10, atol=1e-10 * np.abs(fb).max())
    for got, want in ((a.imp.x, b.imp.x), (a.imp.v, b.imp.v), (a.force, b.force)):
        np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-12 * np.abs(want).max())
    assert a.imp.v[1] == b.imp.v[1] == 0.0  # the held component
    for key in ("kinetic", "internal", "dissipated"):
        assert a.energies()[key] == pytest.approx(b.energies()[key], rel=1e-8, abs=1e-12 * a.energies()["kinetic"])


def test_a_serial_and_a_parallel_build_never_load_each_others_cached_code(tmp_path):
    """numba's disk cache keys a function by its name, bytecode and signature, not by its
    compile options: a parallel build cached first was loaded by the serial build of the same
    function (and a YADE process, whose OpenMP runtime numba must not share, crashed in it).
    Each build has its own cache entry: a process that compiled the parallel build leaves
    nothing the serial build of a later process loads, and the serial build then caches and
    reloads its own."""
    import os
    import subprocess
    import sys
    (tmp_path / "twin.py").write_text(
        "from numba import prange\nfrom physics.compiled import kernel\n\n"
        "def total(x):\n    s = 0.0\n    for i in prange(x.size):\n        s += x[i]\n    return s\n\n"
        "parallel, serial = kernel(parallel=True)(total), kernel(total)\n")
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache"),
           "PYTHONPATH": os.pathsep.join([str(tmp_path), str(ROOT)])}
    run = lambda build: subprocess.run(
        [sys.executable, "-c", f"import numpy as np, twin; twin.{build}(np.ones(8)); "
                               f"print(sum(twin.{build}.stats.cache_hits.values()))"],
        env=env, capture_output=True, text=True, check=True).stdout.split()[-1]
    assert run("parallel") == "0"  # compiled and cached
    assert run("serial") == "0"  # not the parallel build's entry: compiled and cached on its own
    assert run("serial") == "1" and run("parallel") == "1"  # each reloads its own
