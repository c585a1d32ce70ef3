"""Element-level properties: patch tests, mass, stable step, rotation invariance."""
import numpy as np
import pytest
import skfem
from hypothesis import HealthCheck, given, settings, strategies as st

from fem_region import materials
from fem_region.elements import ELEMENTS
from fem_region.region import FemRegion

RNG = np.random.default_rng(1)


def _mesh(name):
    e = ELEMENTS[name]
    if e.dim == 2:
        m = e.mesh_cls.init_tensor(np.linspace(0, 1, 5), np.linspace(0, 0.4, 4))
    else:
        m = e.mesh_cls.init_tensor(np.linspace(0, 1, 4), np.linspace(0, 0.4, 3), np.linspace(0, 0.3, 3))
    # distort interior nodes so the patch test is not trivially on a regular grid
    p = m.p.copy()
    interior = np.all((p > p.min(axis=1, keepdims=True) + 1e-9) & (p < p.max(axis=1, keepdims=True) - 1e-9), axis=0)
    p[:, interior] += 0.02 * RNG.standard_normal((e.dim, interior.sum()))
    return type(m)(p, m.t), interior


@pytest.mark.parametrize("name", ["tri3", "quad4", "tet4", "hex8"])
@pytest.mark.parametrize("integration", ["full", "selective"])
@pytest.mark.parametrize("formulation", ["linear", "total_lagrangian"])
def test_orthotropic_patch(name, integration, formulation):
    """A uniform strain field is reproduced exactly: zero interior force, uniform stress."""
    e = ELEMENTS[name]
    m, interior = _mesh(name)
    ply = materials.transversely_isotropic(156e9, 9.09e9, 0.228, 0.4, 6.9e9)
    angle = 90.0 if e.dim == 2 else 0.0  # selective needs no normal-shear coupling
    D = materials.reduce(materials.rotate(ply, materials.ply_axes(angle, e.dim)), e.dim, "plane_strain")
    r = FemRegion(m, e, D, 1540.0, 0.01, integration, formulation)
    G = 1e-7 * RNG.standard_normal((e.dim, e.dim))  # small enough that TL ~ linear
    u = r.X @ G.T
    f = r.internal_force(u)
    scale = np.abs(f).max()
    assert np.abs(f[interior]).max() < 1e-9 * scale
    eps, sig = r.centroid_strain_stress(u)
    assert np.allclose(eps, eps[0], rtol=0, atol=1e-12 * np.abs(eps).max())


@pytest.mark.parametrize("name", ["tri3", "quad4", "tet4", "hex8"])
def test_lumped_mass_and_rigid_motion(name):
    e = ELEMENTS[name]
    m, _ = _mesh(name)
    r = FemRegion(m, e, materials.reduce(materials.isotropic(1e9, 0.25), e.dim, "plane_strain"), 1000.0, 0.1)
    vol = r.rules[0].dx.sum()
    assert r.mass.sum() == pytest.approx(1000.0 * vol, rel=1e-12)
    assert (r.mass > 0).all()
    # rigid translation and infinitesimal rotation produce no force
    t = np.ones((r.n_nodes, e.dim))
    assert np.abs(r.internal_force(t)).max() < 1e-6
    W = np.zeros((e.dim, e.dim)); W[0, 1], W[1, 0] = 1e-9, -1e-9
    assert np.abs(r.internal_force(r.X @ W.T)).max() < 1e-6 * np.abs(r.K).max() * 1e-9 + 1e-9


def test_total_lagrangian_is_objective():
    """A large rigid rotation produces no force on the TL path (it does on the linear path)."""
    m = skfem.MeshQuad.init_tensor(np.linspace(0, 1, 4), np.linspace(0, 0.2, 3))
    D = materials.plane_strain(materials.isotropic(1e9, 0.3))
    tl = FemRegion(m, ELEMENTS["quad4"], D, 1.0, 1.0, "full", "total_lagrangian")
    th = 0.7
    R = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    u = tl.X @ R.T - tl.X
    assert np.abs(tl.internal_force(u)).max() < 1e-6
    assert tl.strain_energy(u) < 1e-12
    lin = FemRegion(m, ELEMENTS["quad4"], D, 1.0, 1.0, "full", "linear")
    assert np.abs(lin.internal_force(u)).max() > 1e6


def _orthotropic_tl(name: str, integration: str):
    """(element type, Total Lagrangian region on the distorted mesh with an orthotropic ply,
    its D): selective integration is plane only (full in 3D)."""
    e = ELEMENTS[name]
    m, _ = _mesh(name)
    C = materials.orthotropic(156e9, 9.09e9, 9.09e9, 0.228, 0.228, 0.4, 5e9, 5e9, 3.2e9)
    D = materials.plane_strain(C) if e.dim == 2 else C
    if integration == "selective" and e.dim == 3:
        integration = "full"
    return e, FemRegion(m, e, D, 1500.0, 1.0, integration, "total_lagrangian"), D


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.data_too_large])
@given(name=st.sampled_from(["tri3", "quad4", "tet4", "hex8"]), integration=st.sampled_from(["full", "selective"]),
       scale=st.floats(1e-6, 0.3), seed=st.integers(0, 2**31 - 1))
def test_compiled_element_families_equal_the_generic_kernel(name, integration, scale, seed):
    """The Total Lagrangian force of each element family's compiled form (sizes as constants,
    the plane ones in scalars) equals the generic loops bit for bit, from small strain to large
    deformation, on a distorted mesh with an orthotropic material."""
    from fem_region.kernels import VOIGT_2D, VOIGT_3D, total_lagrangian_force, total_lagrangian_force_generic
    e, r, _ = _orthotropic_tl(name, integration)
    rng = np.random.default_rng(seed)
    u = scale * rng.standard_normal((r.n_nodes, e.dim))
    voigt = VOIGT_2D if e.dim == 2 else VOIGT_3D
    for q, Dq in zip(r.rules, r._D_rules):
        fast, ref = np.zeros_like(u), np.zeros_like(u)
        total_lagrangian_force(u, r._conn, q.dN, q.dx, Dq, voigt, fast)
        total_lagrangian_force_generic(u, r._conn, q.dN, q.dx, Dq, voigt, ref)
        assert np.array_equal(fast, ref)
        assert np.abs(ref).max() > 0


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.data_too_large])
@given(name=st.sampled_from(["tri3", "quad4", "tet4", "hex8"]), integration=st.sampled_from(["full", "selective"]),
       scale=st.floats(1e-4, 0.2), seed=st.integers(0, 2**31 - 1))
def test_total_lagrangian_energy_is_the_potential_of_the_internal_force(name, integration, scale, seed):
    """The compiled strain energy and the compiled internal force are two kernels: the energy's
    central difference along any direction is the force's work on it (to the difference's
    truncation), and under a homogeneous deformation F every element's smallest det F is det F
    and the energy is E : C : E / 2 times the volume."""
    e, r, D = _orthotropic_tl(name, integration)
    rng = np.random.default_rng(seed)
    u = scale * rng.standard_normal((r.n_nodes, e.dim)) * 0.05
    du = rng.standard_normal(u.shape)
    h = 1e-6 * (scale + 1e-3)
    dE = (r.strain_energy(u + h * du) - r.strain_energy(u - h * du)) / (2 * h)
    assert dE == pytest.approx(float(np.vdot(r.internal_force(u), du)), rel=1e-5)
    F = np.eye(e.dim) + scale * rng.uniform(-1, 1, (e.dim, e.dim))
    u_affine = r.X @ (F - np.eye(e.dim)).T
    E = 0.5 * (F.T @ F - np.eye(e.dim))
    pairs = [(0, 0), (1, 1), (0, 1)] if e.dim == 2 else [(0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1)]
    Ev = np.array([E[i, j] * (1 if i == j else 2) for i, j in pairs])
    volume = 0.4 if e.dim == 2 else 0.4 * 0.3
    assert r.strain_energy(u_affine) == pytest.approx(0.5 * Ev @ D @ Ev * volume, rel=1e-9)
    det_min = r._total_lagrangian_pass(u_affine)[1]
    assert np.allclose(det_min, np.linalg.det(F), rtol=1e-9)
    assert (r.inverted_elements(u_affine).size == r.n_elements) == (np.linalg.det(F) <= 0)
    # the guard's own kernel finds the elements the energy pass's det F finds, under a field
    # rough enough to turn some inside out
    rough = 0.3 * scale / 0.2 * rng.standard_normal(u.shape) * float(np.ptp(r.X))
    assert np.array_equal(r.inverted_elements(rough), np.flatnonzero(r._total_lagrangian_pass(rough)[1] <= 0.0))


def test_stable_step_bounds_bar_wave_speed():
    """1D limit: the element bound is h / c for a lumped-mass bar element."""
    m = skfem.MeshQuad.init_tensor(np.linspace(0, 1, 11), np.linspace(0, 1, 2))
    E, rho = 2e11, 7800.0
    D = np.diag([E, 0.0, 0.0]) + np.diag([0.0, 1e-6 * E, 1e-6 * E])
    r = FemRegion(m, ELEMENTS["quad4"], D, rho, 1.0, "full")
    assert r.critical_dt() == pytest.approx(0.1 / np.sqrt(E / rho), rel=1e-3)


def test_layup_parsing():
    assert materials.parse_layup("[0_6/90_4/0_6]") == [0.0] * 6 + [90.0] * 4 + [0.0] * 6
    assert materials.parse_layup("[0/90]s") == [0.0, 90.0, 90.0, 0.0]
    assert materials.parse_layup("[45/-45]2s") == [45, -45, 45, -45, -45, 45, -45, 45]
    with pytest.raises(ValueError):
        materials.parse_layup("0/90")


def test_ply_rotation_invariants():
    ply = materials.transversely_isotropic(156e9, 9.09e9, 0.228, 0.4, 6.9e9)
    for angle in (0.0, 30.0, 90.0):
        C = materials.rotate(ply, materials.ply_axes(angle, 3))
        # the isotropic invariants C_iijj and C_ijij of the 4th-order tensor
        assert C[:3, :3].sum() == pytest.approx(ply[:3, :3].sum())
        assert np.trace(C[:3, :3]) + 2 * np.trace(C[3:, 3:]) == pytest.approx(np.trace(ply[:3, :3]) + 2 * np.trace(ply[3:, 3:]))
    C90 = materials.rotate(ply, materials.ply_axes(90.0, 2))
    assert C90[2, 2] == pytest.approx(ply[0, 0])  # 2D: 90 degree fibres run out of plane (z)


@pytest.mark.parametrize("name", ["quad4", "hex8"])
def test_reduced_integration_hourglass_modes(name):
    """One point alone leaves hourglass modes with zero energy; the stiffness control
    removes exactly those and keeps the rigid-body modes."""
    e = ELEMENTS[name]
    m, _ = _mesh(name)
    D = materials.reduce(materials.isotropic(1e9, 0.25), e.dim, "plane_strain")
    rigid = 3 if e.dim == 2 else 6
    n_hg = 1 if e.dim == 2 else 4
    zero = lambda r: int((np.linalg.eigvalsh(r.ke[0]) < 1e-8 * np.linalg.eigvalsh(r.ke[0]).max()).sum())
    free = FemRegion(m, e, D, 1000.0, 1.0, "reduced", hourglass="none")
    ctrl = FemRegion(m, e, D, 1000.0, 1.0, "reduced", hourglass="stiffness")
    assert zero(free) == rigid + n_hg * e.dim
    assert zero(ctrl) == rigid


@pytest.mark.parametrize("name", ["quad4", "hex8"])
@pytest.mark.parametrize("form", ["stiffness", "viscous"])
def test_hourglass_control_passes_patch_test(name, form):
    e = ELEMENTS[name]
    m, interior = _mesh(name)
    D = materials.reduce(materials.isotropic(1e9, 0.25), e.dim, "plane_strain")
    r = FemRegion(m, e, D, 1000.0, 1.0, "reduced", hourglass=form)
    G = 1e-4 * RNG.standard_normal((e.dim, e.dim))
    u = r.X @ G.T
    assert np.abs(r.internal_force(u)[interior]).max() < 1e-9 * np.abs(r.internal_force(u)).max()
    if form == "viscous":  # a uniform velocity gradient is not damped either
        f = np.zeros_like(u)
        r.add_hourglass_viscous_force(u, f)
        assert np.abs(f).max() < 1e-9 * r.hg.c.max()


@pytest.mark.parametrize("name", ["quad4", "hex8"])
@given(seed=st.integers(0, 2**31 - 1), scale=st.floats(1e-6, 1e-2))
@settings(max_examples=10, deadline=None)
def test_compiled_hourglass_and_bulk_viscosity_forces_equal_their_numpy_forms(name, seed, scale):
    """The in-place kernels (the step's: add_hourglass_force, add_bulk_viscosity_force) against
    the readable element forms (HourglassControl.force, BulkViscosity.pressure) scattered by
    np.add.at, on a distorted mesh under a random field of any size."""
    from fem_region.bulk_viscosity import BulkViscosity
    from fem_region.kernels import add_hourglass_force

    e = ELEMENTS[name]
    m, _ = _mesh(name)
    D = materials.reduce(materials.isotropic(1e9, 0.25), e.dim, "plane_strain")
    r = FemRegion(m, e, D, 1000.0, 1.0, "reduced", hourglass="stiffness")
    u = scale * np.random.default_rng(seed).standard_normal((r.n_nodes, e.dim))
    conn = r.mesh.t.T
    ref = np.zeros_like(u)
    np.add.at(ref, conn, r.hg.force(r.hg.k, u[conn]))
    got = np.zeros_like(u)
    add_hourglass_force(r.hg.gamma, r.hg.k, np.ascontiguousarray(conn), u, 1.0, got)
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-12 * np.abs(ref).max())
    bv = BulkViscosity.of(r)
    ref = np.zeros_like(u)
    np.add.at(ref, conn, -bv.pressure(u)[:, None, None] * bv.b * bv.vol[:, None, None])
    assert np.abs(ref).max() > 0  # some elements in compression
    np.testing.assert_allclose(bv.force(u), ref, rtol=0, atol=1e-12 * np.abs(ref).max())


def test_failure_indices_closed_forms():
    from physics import failure
    k = failure.HoffmanStrengths(2000e6, 1200e6, 50e6, 200e6, 50e6, 200e6, 60e6, 80e6, 80e6)
    for comp, strengths in ((0, (k.Xt, -k.Xc)), (1, (k.Yt, -k.Yc)), (2, (k.Zt, -k.Zc))):
        for s in strengths:
            sig = np.zeros(6)
            sig[comp] = s
            assert failure.hoffman(sig, k) == pytest.approx(1.0)
    for comp, s in ((3, k.S23), (4, k.S13), (5, k.S12)):
        sig = np.zeros(6)
        sig[comp] = s
        assert failure.hoffman(sig, k) == pytest.approx(1.0)
    # Hashin interlaminar: tension at Z0 or shear at R0 initiates; compression alone does not
    assert failure.hashin_interlaminar(np.array([0, 0, 40e6, 0, 0, 0]), 40e6, 20e6) == pytest.approx(1.0)
    assert failure.hashin_interlaminar(np.array([0, 0, -400e6, 0, 0, 0]), 40e6, 20e6) == 0.0
    assert failure.hashin_interlaminar(np.array([0, 0, 0, 12e6, 16e6, 0]), 40e6, 20e6) == pytest.approx(1.0)
    # rotating a uniaxial fibre stress into the axes of a 90 degree 2D ply puts it along 2
    R = materials.ply_axes(90.0, 2)
    sz = np.array([0, 0, 5.0, 0, 0, 0])  # global z = out of plane = fibre of a 90 ply in 2D
    assert failure.to_ply_axes(sz, R)[0] == pytest.approx(5.0)


def test_laminate_blocks_follow_layup():
    from fem_region.laminate import Laminate, beam_mesh_2d
    ply = materials.transversely_isotropic(156e9, 9.09e9, 0.228, 0.4, 6.9e9)
    lam = Laminate.from_layup("[0_6/90_4/0_6]", 0.125e-3, ply)
    m, plies = beam_mesh_2d(0.05, lam, 20, per_ply=2)
    assert lam.thickness == pytest.approx(2e-3)
    assert [i for i, _ in lam.interfaces()] == [5, 9]
    assert np.bincount(plies).tolist() == [40] * 16
    C = lam.global_C(plies, 2)
    angles = np.array(lam.angles)[plies]
    assert np.allclose(C[angles == 0][:, 0, 0], 156e9 * 0 + ply[0, 0])
    assert np.allclose(C[angles == 90][:, 2, 2], ply[0, 0])  # 90 plies: fibres out of plane


def test_stress_3d_plane_hypotheses():
    C = materials.isotropic(100e9, 0.25)[None]
    eps = np.array([[1e-3, 0.0, 0.0]])
    s_strain = materials.stress_3d(eps, C, 2, "plane_strain")[0]
    s_stress = materials.stress_3d(eps, C, 2, "plane_stress")[0]
    assert s_strain[2] == pytest.approx(0.25 * s_strain[0] / 0.75)  # sigma_zz = nu (sxx + syy)
    assert s_stress[2] == 0.0 and s_stress[0] == pytest.approx(100e9 / (1 - 0.25**2) * 1e-3)


def _turned_numbering(m: skfem.MeshHex, turns: np.ndarray) -> skfem.MeshHex:
    """The same mesh with element e's corners numbered after turns[e] quarter turns of the
    reference cube (axes cycled (a, b, c) -> (b, c, a)): another orientation, the same element."""
    dl = skfem.ElementHex1().doflocs
    cycle = [int(np.flatnonzero((dl == dl[a][[1, 2, 0]]).all(axis=1))[0]) for a in range(8)]
    t = m.t.copy()
    for e, k in enumerate(turns):
        for _ in range(int(k)):
            t[:, e] = t[cycle, e]
    return skfem.MeshHex(m.p, t)


@settings(max_examples=12, deadline=None)
@given(n=st.tuples(*[st.integers(1, 3)] * 3), size=st.tuples(*[st.floats(0.2e-3, 5e-3)] * 3),
       seed=st.integers(0, 2**31 - 1))
def test_selective_hexahedra_have_no_spurious_zero_energy_modes(n, size, seed):
    """Hex8 with selective integration: only the six rigid motions carry no energy (shear at the
    centroid alone left the three twist modes u_x = y z, u_y = x z, u_z = x y free: nine), whatever
    the mesh's sizes and however each element's corners are numbered (the stiffness is the same)."""
    rng = np.random.default_rng(seed)
    m = skfem.MeshHex.init_tensor(*[np.cumsum(np.r_[0.0, rng.uniform(0.5, 1.5, k)]) * s for k, s in zip(n, size)])
    D = materials.orthotropic(140e9, 9.5e9, 9.5e9, 0.3, 0.3, 0.4, 5.5e9, 5.5e9, 3.4e9)
    r = FemRegion(m, ELEMENTS["hex8"], D, 1500.0, 1.0, "selective")
    K = r.K.toarray()
    w = np.linalg.eigvalsh(K)
    assert int((w < 1e-9 * w.max()).sum()) == 6
    turned = FemRegion(_turned_numbering(m, rng.integers(0, 3, m.t.shape[1])), ELEMENTS["hex8"], D, 1500.0, 1.0,
                       "selective")
    assert np.allclose(turned.K.toarray(), K, rtol=0, atol=1e-9 * np.abs(K).max())


@pytest.mark.parametrize("axis, bend", [(a, b) for a in range(3) for b in range(3) if a != b])
def test_selective_hexahedra_bend_without_shear_locking(axis, bend):
    """A cantilever of one element through its depth, along each axis and bent in each other
    direction: the tip deflection within 1 % of Timoshenko's beam (bending and shear) with
    selective integration; fully integrated it locks (below 0.75 of it)."""
    L, H, E, nu, P = 10e-3, 1e-3, 1e9, 0.0, 1e-3
    edges = [np.linspace(0, H, 2)] * 3
    edges[axis] = np.linspace(0, L, 11)
    m = skfem.MeshHex.init_tensor(*edges)
    D = materials.isotropic(E, nu)
    exact = P * L**3 / (3 * E * H**4 / 12) + P * L / (5 / 6 * E / (2 * (1 + nu)) * H * H)
    ratio = {}
    for integration in ("full", "selective"):
        r = FemRegion(m, ELEMENTS["hex8"], D, 1.0, 1.0, integration)
        X = r.X
        fixed, tip = np.flatnonzero(np.isclose(X[:, axis], 0)), np.flatnonzero(np.isclose(X[:, axis], L))
        F = np.zeros((r.n_nodes, 3))
        F[tip, bend] = P / len(tip)
        free = np.setdiff1d(np.arange(3 * r.n_nodes), (3 * fixed[:, None] + np.arange(3)).ravel())
        u = np.zeros(3 * r.n_nodes)
        K = r.K.tocsr()
        u[free] = np.linalg.solve(K[free][:, free].toarray(), F.ravel()[free])
        ratio[integration] = u.reshape(-1, 3)[tip, bend].mean() / exact
    assert ratio["selective"] == pytest.approx(1.0, abs=0.01)
    assert ratio["full"] < 0.75
