"""Explicit dynamics: impactors, damping options, mass scaling, loads (invariants and closed forms)."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fem_region import loads, materials, mesh
from fem_region.bulk_viscosity import BulkViscosity
from fem_region.elements import ELEMENTS
from fem_region.explicit import ExplicitDynamics, PrescribedMotion, at_rest
from physics.impactor import RigidImpactor
from fem_region.region import FemRegion


def _block(dim=2, n=6, E=1e9, rho=1000.0, integration="full"):
    if dim == 2:
        m = mesh.rectangle(np.linspace(0, 0.1, n + 1), np.linspace(0, 0.05, n // 2 + 1))
    else:
        m = mesh.box(np.linspace(0, 0.1, n + 1), np.linspace(0, 0.1, n + 1), np.linspace(0, 0.05, n // 2 + 1))
    D = materials.reduce(materials.isotropic(E, 0.3), dim, "plane_strain")
    return FemRegion(m, ELEMENTS["quad4" if dim == 2 else "hex8"], D, rho, 0.01 if dim == 2 else 1.0, integration)


def _run(dyn, steps, safety=0.9):
    dt = safety * dyn.critical_dt()
    dyn.start()
    for _ in range(steps):
        dyn.step(dt)
    return dt


@pytest.mark.parametrize("dim, shape, friction", [(2, "cylinder", 0.0), (2, "cylinder", 0.3),
                                                  (3, "sphere", 0.2), (2, "flat_punch", 0.0), (3, "rod", 0.0)])
def test_impactor_conserves_momentum(dim, shape, friction):
    """A free block hit by a rigid impactor: total momentum is conserved to round-off, an
    elastic impact conserves energy (penalty energy included), friction only dissipates."""
    r = _block(dim)
    top = 0.05
    c = np.array([0.05, top + 0.01] if dim == 2 else [0.05, 0.05, top + 0.01])
    v = np.zeros(dim)
    v[dim - 1] = -20.0
    if shape in ("cylinder", "sphere"):
        v[0] = 3.0  # oblique, so friction acts
        imp = RigidImpactor(shape, c, 0.0099, 0.05, v, penalty=5e7, friction=friction)
    else:  # flat faces push nodes that come through the face, so the motion is normal to it
        c[dim - 1] = top + 2e-4
        axis = np.zeros(dim)
        axis[dim - 1] = 1.0
        imp = RigidImpactor(shape, c, 0.02, 0.05, v, penalty=5e7, friction=friction, axis=axis, depth=0.005)
    dyn = ExplicitDynamics(r, impactors=[imp])
    p0 = dyn.momentum().copy()
    e0 = dyn.impactors[0].mass * v @ v / 2
    _run(dyn, 720, safety=0.5)  # at 0.9 the stiffest contact loses ~2 % (converges with dt)
    assert np.abs(imp.v - v).max() > 0.5, "the impactor must have hit the block"
    # internal forces sum to zero only to round-off (eps |f|) at each of the 720 steps
    assert np.abs(dyn.momentum() - p0).max() <= 1e-10 * np.abs(p0).max()
    e = dyn.energies()
    if friction == 0.0:  # elastic: what is not kinetic or strain energy is stored in the penalty
        assert abs(e["kinetic"] + e["internal"] - e0) < 0.02 * e0
    assert e["dissipated"] > -0.01 * e0, "contact must not create energy"


class _GapForm(RigidImpactor):
    ball = on_nodes_compiled = False  # the readable gap form on gathered nodes, not the compiled pass


@pytest.mark.parametrize("dim, shape, friction, axis", [(2, "cylinder", 0.3, None), (3, "sphere", 0.2, None),
                                                       (3, "cylinder", 0.25, (0.3, 1.0, 0.1))])
def test_compiled_ball_on_the_surface_is_the_gathered_gap_form(dim, shape, friction, axis):
    """The ball's (or a cylinder's, along an oblique axis) one-pass contact on the FEM's surface
    nodes (kernels.impactor_on_nodes) steps the block as the gap form on the gathered nodes does:
    nodes, impactor and contact ledger equal to round-off over an oblique impact with friction
    (the force on the ball and the work are summed in another order)."""
    runs = []
    for kind in (RigidImpactor, _GapForm):
        c = np.array([0.05, 0.06] if dim == 2 else [0.05, 0.05, 0.06])
        v = np.zeros(dim)
        v[0], v[dim - 1] = 3.0, -20.0
        imp = kind(shape, c, 0.0099, 0.05, v, penalty=5e7, friction=friction, axis=axis)
        dyn = ExplicitDynamics(_block(dim), impactors=[imp])
        _run(dyn, 300, safety=0.5)
        assert np.abs(imp.v - v).max() > 0.5  # it hit
        runs.append((dyn, imp))
    (a, ia), (b, ib) = runs
    scale = np.abs(b.state.u).max()
    assert np.abs(a.state.u - b.state.u).max() <= 1e-9 * scale
    assert np.abs(ia.v - ib.v).max() <= 1e-9 * np.abs(ib.v).max()
    for k in ("kinetic", "internal", "dissipated"):
        assert a.energies()[k] == pytest.approx(b.energies()[k], rel=1e-8, abs=1e-12)


@pytest.mark.parametrize("dim, shape, footprint", [(2, "flat_punch", False), (3, "rod", False), (3, "rod", True)])
def test_compiled_flat_face_on_the_surface_is_the_gathered_gap_form(dim, shape, footprint):
    """A flat face pressed obliquely into the block with friction, its penalty on every node
    under it or a footprint of its own per node: the compiled pass (kernels.flat_contact) steps
    it as the gap form on the gathered nodes does, nodes, impactor, stored penalty energy (at
    every step) and ledger to round-off."""
    r = _block(dim)
    top = 0.05
    pair = []
    for kind in (RigidImpactor, _GapForm):
        c = np.array([0.05, top + 2e-4] if dim == 2 else [0.05, 0.05, top + 2e-4])
        v = np.zeros(dim)
        v[0], v[dim - 1] = 2.0, -20.0
        axis = np.zeros(dim)
        axis[dim - 1] = 1.0
        k = None
        if footprint:  # a share of the face's penalty per node within it, by its distance from the axis
            lateral = np.linalg.norm((r.X - c)[:, : dim - 1], axis=1)
            k = np.where(lateral <= 0.02, 5e7 * (1.5 - lateral / 0.02), 0.0)
        imp = kind(shape, c, 0.02, 0.05, v, penalty=5e7, friction=0.25, axis=axis, depth=0.005, footprint=k)
        dyn = ExplicitDynamics(r, impactors=[imp])
        dyn.start()
        pair.append((dyn, imp))
    (a, ia), (b, ib) = pair
    dt, stored = 0.5 * a.critical_dt(), []
    for _ in range(300):
        a.step(dt)
        b.step(dt)
        assert a._contact_energy == pytest.approx(b._contact_energy, rel=1e-9, abs=1e-15)
        stored.append(a._contact_energy)
    assert max(stored) > 0 and np.abs(ia.v - v).max() > 0.5  # it pressed in, and it hit
    assert np.abs(a.state.u - b.state.u).max() <= 1e-9 * np.abs(b.state.u).max()
    assert np.abs(ia.v - ib.v).max() <= 1e-9 * np.abs(ib.v).max()
    for key in ("kinetic", "internal", "dissipated"):
        assert a.energies()[key] == pytest.approx(b.energies()[key], rel=1e-8, abs=1e-12)


def test_fixed_and_moving_supports_set_their_velocities_in_order():
    """The fixed supports' DOFs are set in one operation, then the moving ones: the same
    velocities as setting every support in its order, also when a DOF is both fixed and moving
    (then each is set in turn: the last support's wins)."""
    r = _block(2)
    n = r.n_nodes
    left, right = np.arange(0, 2 * n, 14), np.arange(1, 2 * n, 10)
    for supports in ([PrescribedMotion(left), PrescribedMotion(right, lambda t: 2.0 * t)],
                     [PrescribedMotion(right, lambda t: 2.0 * t), PrescribedMotion(np.union1d(left, right[:3]))]):
        dyn = ExplicitDynamics(r, supports=supports)
        dyn.state.v[:] = 7.0
        dyn._set_prescribed_velocities(0.5)
        ref = np.full(2 * n, 7.0)
        for sup in supports:
            ref[sup.dofs] = sup.velocity(0.5)
        np.testing.assert_array_equal(dyn.state.v.reshape(-1), ref)


def test_penalty_enters_stable_step():
    r = _block()
    soft = ExplicitDynamics(r, impactors=[RigidImpactor("cylinder", [0.05, 0.07], 0.01, 1.0, [0, -1], penalty=1e3)])
    stiff = ExplicitDynamics(r, impactors=[RigidImpactor("cylinder", [0.05, 0.07], 0.01, 1.0, [0, -1], penalty=1e12)])
    assert soft.critical_dt() == pytest.approx(ExplicitDynamics(r).critical_dt())
    m_min = stiff.m[r.mesh.boundary_nodes()].min()
    assert stiff.critical_dt() == pytest.approx(2 / np.sqrt(1e12 * (1 / m_min + 1)))


def test_mass_scaling_reaches_target_and_reports_added_mass():
    r = _block()
    target = 3 * r.critical_dt()
    dyn = ExplicitDynamics(r, mass_scaling_dt=target)
    assert dyn.critical_dt() >= target  # the assembled step: at least every element's own
    assert r.element_critical_dt() * np.sqrt(dyn.density_scale) == pytest.approx(target, rel=1e-9)
    assert dyn.added_mass.sum() == pytest.approx(8 * r.mass.sum(), rel=1e-9)  # uniform mesh: factor 9


def test_bulk_viscosity_dissipates_only_in_compression():
    r = _block()
    bv = BulkViscosity.of(r)
    X = r.X
    compress = -(X - X.mean(axis=0))  # uniform contraction rate
    expand = -compress
    assert (bv.pressure(compress) > 0).all() and (bv.pressure(expand) == 0).all()
    f = bv.force(compress)
    assert np.vdot(f, compress) > 0  # subtracted like a damping force: it dissipates
    assert np.abs(f.sum(axis=0)).max() < 1e-12 * np.abs(f).max()  # internal: no net force


def test_rayleigh_mass_damping_decay_rate():
    """alpha M damping: a rigid translation decays as exp(-alpha t) (closed form)."""
    r = _block()
    dyn = ExplicitDynamics(r, alpha=500.0)
    dyn.set_initial_velocity(np.tile([1.0, 0.0], (r.n_nodes, 1)))
    n = 200
    dt = _run(dyn, n)
    # the lagged damping velocity makes a first-order error of about n (alpha dt)^2 / 2
    assert dyn.state.v[:, 0].mean() == pytest.approx(np.exp(-500.0 * n * dt), rel=n * (500.0 * dt) ** 2)


def test_tabulated_curve_and_surface_traction(tmp_path):
    csv = tmp_path / "curve.csv"
    csv.write_text("# demo\ntime_ms,load_kN\n0,0\n1,2\n2,0\n")
    c = loads.tabulated(csv, 1e-3, 1e3)
    assert c(0.5e-3) == pytest.approx(1000.0) and c(3e-3) == 0.0 and c(-1) == 0.0
    r = _block()
    load = loads.surface_traction(r, lambda x: x[1] > 0.05 - 1e-9, [0.0, -2e6], c)
    total = np.asarray(load.amplitude).reshape(-1, 2).sum(axis=0)
    assert total == pytest.approx([0.0, -2e6 * 0.1 * 0.01])  # traction x edge length x width
    drop = loads.tabulated("/work/shared/reference/cfrp_beam_drop_load.csv", 1e-3, 1e3) \
        if __import__("os").path.exists("/work/shared/reference/cfrp_beam_drop_load.csv") else None
    if drop is not None:
        assert drop(0.3e-3) == pytest.approx(35.6e3)


def test_gmsh_mesh_round_trip(tmp_path):
    """Meshes come in through meshio: write a Gmsh file, read it back as an FEM region."""
    import meshio
    m = mesh.rectangle(np.linspace(0, 1, 4), np.linspace(0, 1, 3), "tri3")
    path = tmp_path / "m.msh"
    meshio.write(path, meshio.Mesh(m.p.T, [("triangle", m.t.T)]), file_format="gmsh22", binary=False)
    back = mesh.read(path)
    assert mesh.element_name(back) == "tri3" and back.t.shape == m.t.shape
    r = FemRegion(back, ELEMENTS["tri3"], materials.plane_stress(materials.isotropic(1e9, 0.3)), 1.0, 1.0)
    assert r.mass.sum() == pytest.approx(1.0)


def test_graded_coordinates():
    xs = mesh.graded(0.0, 1.0, 20, ratio=1.2, toward=0.5)
    h = np.diff(xs)
    assert xs[0] == 0 and xs[-1] == 1 and len(xs) == 21
    assert h.min() == pytest.approx(h[9]) or h.min() == pytest.approx(h[10])
    assert h.max() / h.min() == pytest.approx(1.2**9, rel=1e-6)


def test_prescribed_displacement_history_is_followed():
    from fem_region.explicit import displacement_history
    r = _block()
    right = r.nodes_where(lambda x: x[0] > 0.1 - 1e-9)
    d = lambda t: 1e-4 * np.sin(2e3 * t)  # midpoint-rule error ~ (omega dt)^2 / 24 per step
    dyn = ExplicitDynamics(r, supports=[PrescribedMotion(right * 2, displacement_history(d))])
    dt = _run(dyn, 300)
    assert dyn.state.u[right, 0] == pytest.approx(np.full(len(right), d(300 * dt)), abs=1e-3 * 1e-4)


def test_laminated_plate_mesh():
    from fem_region.laminate import Laminate, plate_mesh_3d
    lam = Laminate.from_layup("[0/90]s", 0.25e-3, materials.transversely_isotropic(140e9, 10e9, 0.3, 0.4, 5e9))
    m, ply = plate_mesh_3d(0.1, 0.1, lam, 8, 8, per_ply=1, grade_ratio=1.3, center=(0.05, 0.05))
    assert np.bincount(ply).tolist() == [64] * 4
    C = lam.global_C(ply, 3)
    assert np.allclose(C[ply == 1][:, 1, 1], C[ply == 0][:, 0, 0])  # 90 plies: fibres along y in 3D


def test_inverted_elements_are_found():
    r = _block()
    u = np.zeros((r.n_nodes, 2))
    assert r.inverted_elements(u).size == 0
    # push one interior node through its neighbours: the elements around it turn inside out
    node = r.nodes_where(lambda x: (np.abs(x[0] - 0.05) < 1e-9) & (np.abs(x[1] - 0.05 / 3) < 1e-9))[0]
    u[node] = [0.0, -0.04]
    bad = r.inverted_elements(u)
    assert bad.size > 0 and all(node in r.mesh.t[:, e] for e in bad)


@settings(max_examples=8, deadline=None)
@given(steps=st.integers(120, 600), E=st.floats(0.3e9, 5e9), load=st.floats(10.0, 1e4))
def test_a_ramped_load_s_work_closes_the_ledger(steps, E, load):
    """A block clamped on one side, its other side pulled by nodal loads ramping from zero over
    ``steps`` steps, undamped: the loads' work (the trapezoid of consecutive loads on each step's
    motion) equals the kinetic plus strain energy to the scheme's O(dt^2). Taking this step's
    load twice instead of the last one and this one, an error of about dt / T (1 / steps) of
    the work, fails it (the buffers of consecutive loads confused); any ramp, modulus and load."""
    from fem_region.explicit import NodalLoad
    r = _block(2, E=E)
    X = r.X
    left, right = np.flatnonzero(np.isclose(X[:, 0], 0.0)), np.flatnonzero(np.isclose(X[:, 0], 0.1))
    dyn = ExplicitDynamics(r, supports=[PrescribedMotion(np.concatenate([2 * left, 2 * left + 1]))])
    dt = 0.9 * dyn.critical_dt()
    T = steps * dt
    dyn.loads.append(NodalLoad(2 * right, np.full(len(right), load), lambda t: min(t / T, 1.0)))
    _run(dyn, steps)
    e = dyn.energies()
    assert e["external_work"] > 0
    assert abs(e["external_work"] - e["kinetic"] - e["internal"]) < 2e-4 * e["external_work"], e


@settings(max_examples=30, deadline=None)
@given(n=st.integers(2, 40), dim=st.sampled_from([2, 3]), seed=st.integers(0, 2**32 - 1), share=st.floats(0.05, 1.0))
def test_the_support_pass_is_the_reaction_and_trapezoidal_work_of_its_dofs(n, dim, seed, share):
    """fem_region.kernels.support_reaction against its definition in numpy: on the prescribed
    DOFs, reaction = m a_pres - f, a = a_pres, work = (reaction_prev + reaction) . du / 2; every
    other DOF's acceleration untouched."""
    from fem_region.kernels import support_reaction
    rng = np.random.default_rng(seed)
    f, du, a = (rng.standard_normal((n, dim)) for _ in range(3))
    dofs = np.flatnonzero(rng.random(n * dim) < share)
    m, a_pres, prev = rng.random(dofs.size) + 0.1, rng.standard_normal(dofs.size), rng.standard_normal(dofs.size)
    a0, reaction = a.copy(), np.zeros(dofs.size)
    work = support_reaction(f, du, a, dofs, m, a_pres, prev, reaction)
    expected = m * a_pres - f.reshape(-1)[dofs]
    assert np.allclose(reaction, expected, rtol=1e-14, atol=1e-14)
    assert work == pytest.approx(0.5 * np.dot(prev + expected, du.reshape(-1)[dofs]), rel=1e-12, abs=1e-12)
    a_expected = a0.reshape(-1).copy()
    a_expected[dofs] = a_pres
    assert np.array_equal(a.reshape(-1), a_expected)


def _energy_ratio(kappa: float, aspect: float, seed: int, dt: float | None = None) -> float:
    """(kinetic + strain energy) after 3,000 steps over at the start of a free strip of one-point
    Q4 of a 0 ply (E11 / E22 = 17), elements ``aspect`` x longer than high, with the viscous
    hourglass form of coefficient kappa, set moving at random; at dt (default: 0.9 x the stable
    step, the form's damping in it)."""
    h = 0.15e-3
    m = mesh.rectangle(np.linspace(0, 12 * aspect * h, 13), np.linspace(0, 4 * h, 5))
    D = materials.reduce(materials.orthotropic(156e9, 9.09e9, 9.09e9, 0.228, 0.228, 0.4, 4.5e9, 4.5e9, 3.25e9),
                         2, "plane_stress")
    r = FemRegion(m, ELEMENTS["quad4"], D, 1540.0, 1e-3, "reduced", hourglass="viscous", hourglass_kappa=kappa)
    dyn = ExplicitDynamics(r)
    dyn.state.v[:] = np.random.default_rng(seed).normal(size=dyn.state.v.shape)
    if dt is None:
        dt = 0.9 * dyn.critical_dt()
    dyn.start()
    e0 = dyn.energies()
    for _ in range(3000):
        dyn.step(dt)
    e = dyn.energies()
    return (e["kinetic"] + e["internal"]) / (e0["kinetic"] + e0["internal"])


@settings(max_examples=8, deadline=None)
@given(kappa=st.floats(0.01, 1.0), aspect=st.floats(0.5, 8.0), seed=st.integers(0, 2**31))
def test_the_viscous_hourglass_form_is_within_the_stable_step(kappa, aspect, seed):
    """Over fem.hourglass_kappa's range and elements up to 8 x longer than high: at the stable
    step, which counts the viscous form's damping, the energy only falls."""
    assert _energy_ratio(kappa, aspect, seed) <= 1.0 + 1e-9


def test_the_viscous_hourglass_form_needs_its_damping_in_the_step():
    """The control: the seed beam's far-field elements (6.7 x longer than a ply is thick, kappa
    0.1) at the step of their stiffness alone, as the beams took it before, gain energy without
    bound (its hourglass modes have no stiffness; the damping alone limits the step)."""
    from fem_region.stable_step import assembled_critical_dt
    h = 0.15e-3
    m = mesh.rectangle(np.linspace(0, 12 * 6.7 * h, 13), np.linspace(0, 4 * h, 5))
    D = materials.reduce(materials.orthotropic(156e9, 9.09e9, 9.09e9, 0.228, 0.228, 0.4, 4.5e9, 4.5e9, 3.25e9),
                         2, "plane_stress")
    r = FemRegion(m, ELEMENTS["quad4"], D, 1540.0, 1e-3, "reduced", hourglass="viscous", hourglass_kappa=0.1)
    undamped = 0.9 * assembled_critical_dt(r.K, r.mass, 2)
    assert not _energy_ratio(0.1, 6.7, 0, undamped) <= 1.0  # (nan: it overflowed)


class _NodeForces:
    """A node-force model (ExplicitDynamics.node_forces): forces (n, 3) N of a linear spring
    field on the nodes' displacements, padded to three columns as law bonds on nodes leave them."""

    def __init__(self, dyn, k: float, seed: int):
        self.dyn, self.k = dyn, k
        self.w = np.random.default_rng(seed).uniform(0.5, 1.5, size=(dyn.region.n_nodes, 1))
        self.f = np.zeros((dyn.region.n_nodes, 3))

    def __call__(self):
        self.f[:, : self.dyn.region.dim] = -self.k * self.w * self.dyn.state.u
        return self.f


@settings(max_examples=12, deadline=None, derandomize=True)
@given(dim=st.sampled_from([2, 3]), models=st.integers(0, 2), seed=st.integers(0, 2**31), moving=st.booleans())
def test_the_force_evaluation_is_its_steps_written_out(dim, models, seed, moving):
    """ExplicitDynamics.compute_forces (its compiled start and finish: kernels.residual_start /
    residual_finish) against its steps in numpy: f = -K u + the node-force models' sum, a = f / m
    off the prescribed DOFs, the supports' reaction m a_pres - f on them and its trapezoidal work,
    over a few steps of a block with a fixed edge, a moving one or none, and 0-2 node-force
    models; and the clock's fused kicks and drift (respa_drift) against respa_kicks then drift."""
    from fem_region.kernels import respa_kicks
    rng = np.random.default_rng(seed)
    r = _block(dim, n=4)
    X = r.X
    left = np.flatnonzero(np.isclose(X[:, 0], 0.0))
    dofs = (left[:, None] * dim + np.arange(dim)).ravel()
    supports = [PrescribedMotion(dofs, (lambda t: 0.3 * t) if moving else at_rest)]
    dyn = ExplicitDynamics(r, supports=supports)
    dyn.node_forces = [_NodeForces(dyn, 1e8, seed + k) for k in range(models)]
    dyn.start()
    ref = dyn.ledger.support_work
    u_at, r_prev = np.zeros_like(dyn.state.u), np.zeros(dofs.size)
    dt = 0.5 * dyn.critical_dt()
    for step in range(4):
        dyn.state.v[:] = rng.normal(size=dyn.state.v.shape)
        dyn.kick_drift(dt)
        u = dyn.state.u.copy()
        dyn.compute_forces()
        f = -(r.K @ u.ravel()).reshape(u.shape)
        for model in dyn.node_forces:
            f += model()[:, :dim]
        a = f / dyn.m[:, None]
        t = dyn.state.t
        a_pres = np.full(dofs.size, 0.3 if moving else 0.0)  # (v = 0.3 t)
        a.reshape(-1)[dofs] = a_pres
        reaction = dyn.m.repeat(dim)[dofs] * a_pres - f.reshape(-1)[dofs]
        ref += 0.5 * float(np.sum((r_prev + reaction) * (u - u_at).reshape(-1)[dofs]))
        np.testing.assert_allclose(dyn.state.a, a, rtol=1e-12, atol=1e-12 * np.abs(a).max())
        np.testing.assert_allclose(dyn._reaction_prev, reaction, rtol=1e-12, atol=1e-12 * np.abs(reaction).max())
        assert dyn.ledger.support_work == pytest.approx(ref, rel=1e-10, abs=1e-20)
        np.testing.assert_array_equal(dyn._u_at_forces, u)
        u_at, r_prev = u, reaction
        assert t == dyn.state.t
    # the fused kicks and drift against the two steps, from the same state
    f_tie = rng.normal(size=dyn.state.v.shape)
    outs = []
    for fused in (True, False):
        d = ExplicitDynamics(r, supports=supports)
        d.state.u[:], d.state.v[:], d.state.a[:] = dyn.state.u, dyn.state.v, dyn.state.a
        f_fast, a_slow = np.zeros_like(f_tie), np.zeros_like(f_tie)
        if fused:
            d.respa_drift(0.5 * dt, f_tie, np.zeros((0, dim)), dt, True, f_fast, a_slow)
        else:
            respa_kicks(d.state.v, d.state.a, f_tie, np.zeros((0, dim)), d.m, dt, 0.5 * dt, True, True, f_fast, a_slow)
            d.drift(0.5 * dt)
        outs.append((d.state.u.copy(), d.state.v.copy(), d.state.t, f_fast, a_slow))
    for got, want in zip(*outs):
        np.testing.assert_array_equal(got, want)
