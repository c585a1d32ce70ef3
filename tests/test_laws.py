"""Interlaminar cohesive law: closed forms of a single bond (energy, initiation, irreversibility)."""
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from physics.laws import HashinCohesiveLaw, friction_traction

# AS4/PEEK (VALIDATION.md: Camanho & Davila / Turon), penalty 1e14 Pa/m
AS4 = HashinCohesiveLaw(K=1e14, Z0=80e6, R0=100e6, GIc=969.0, GIIc=1719.0, eta=2.284)


def dissipate(law, direction, n=20000, incremental=True):
    """Drive one bond along a proportional path (dn, ds) = s * direction to full decohesion;
    returns (work J/m^2, peak tractions, damage). ``incremental=False``: the path's n points as
    n bonds in one call, each from zero damage; on a monotonic proportional path a point's
    damage is the path's up to it, so the tractions are the same (irreversibility is tested
    on the incremental path)."""
    a, b = direction
    m0, mf, _ = law.onset_and_final(np.array([a]), np.array([abs(b)]))
    s = np.linspace(0, 1.2 * mf[0] / np.hypot(max(a, 0), b), n)
    if incremental:
        d, tn, ts = np.zeros(1), np.zeros(n), np.zeros(n)
        for k in range(1, n):
            tk, sk, d = law.tractions(np.array([a * s[k]]), np.array([[b * s[k]]]), d)
            tn[k], ts[k] = tk[0], sk[0, 0]
    else:
        tn, ts, d = law.tractions(a * s, (b * s)[:, None], np.zeros(n))
        tn, ts, d = tn.copy(), ts[:, 0].copy(), d[-1:]
        tn[0] = ts[0] = 0.0
    work = float(np.sum(0.5 * ((tn[1:] + tn[:-1]) * a + (ts[1:] + ts[:-1]) * b) * np.diff(s)))
    k = int(np.argmax(np.hypot(tn, ts)))
    return work, (tn[k], ts[k]), d[0]


@pytest.mark.parametrize("direction, G", [((1.0, 0.0), 969.0), ((0.0, 1.0), 1719.0)])
def test_pure_modes_dissipate_their_toughness(direction, G):
    work, peak, d = dissipate(AS4, direction)
    assert d == 1.0
    assert work == pytest.approx(G, rel=1e-3)
    assert np.hypot(*peak) == pytest.approx(80e6 if direction[0] else 100e6, rel=1e-3)


@settings(max_examples=20, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.data_too_large, HealthCheck.too_slow])
@given(beta=st.floats(0.05, 20.0), Z0=st.floats(10e6, 100e6), R0=st.floats(10e6, 100e6),
       GIc=st.floats(100.0, 2000.0), ratio=st.floats(1.0, 4.0), mode=st.sampled_from(["bk", "power"]))
def test_mixed_mode_dissipation_and_initiation(beta, Z0, R0, GIc, ratio, mode):
    """Proportional mixed-mode loading dissipates Gc(B) of the chosen criterion, and the
    traction at onset satisfies Hashin's quadratic criterion."""
    law = HashinCohesiveLaw(K=1e14, Z0=Z0, R0=R0, GIc=GIc, GIIc=ratio * GIc, mixed_mode=mode)
    work, peak, d = dissipate(law, (1.0, beta), n=6000, incremental=False)
    B = beta**2 / (1 + beta**2)
    assert d == 1.0
    assert work == pytest.approx(float(law.toughness(B)), rel=5e-3)
    assert (peak[0] / Z0) ** 2 + (peak[1] / R0) ** 2 == pytest.approx(1.0, rel=5e-3)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.data_too_large])
@given(beta=st.floats(0.0, 10.0), f=st.floats(0.0, 0.99), ratio=st.floats(0.02, 1.0), Z0=st.floats(10e6, 100e6),
       R0=st.floats(10e6, 100e6), GIc=st.floats(300.0, 2000.0), mode=st.sampled_from(["bk", "power"]))
def test_a_softening_state_carries_onto_another_stiffness(beta, f, ratio, Z0, R0, GIc, mode):
    """A bond loaded a fraction f of the way from onset to full decohesion, carried onto a
    law of the same strengths and toughness but another penalty (a cohesive node pair's state
    onto a particle bond, study/growth.py; HashinCohesiveLaw.damage_on): reloaded from closed, the new bond peaks at (1 - f)
    of the mode mix's onset traction and dissipates (1 - f) Gc(B) on its way to decohesion."""
    stiff = HashinCohesiveLaw(K=1e15, Z0=Z0, R0=R0, GIc=GIc, GIIc=1.5 * GIc, mixed_mode=mode)
    soft = HashinCohesiveLaw(K=ratio * 1e15, Z0=Z0, R0=R0, GIc=GIc, GIIc=1.5 * GIc, mixed_mode=mode)
    a, b = 1.0, beta
    one = lambda x: np.array([x])
    m0, mf, B = (float(x[0]) for x in stiff.onset_and_final(one(a), one(b)))
    m = m0 + f * (mf - m0)
    _, _, d = stiff.tractions(one(a * m / np.hypot(a, b)), one(b * m / np.hypot(a, b))[:, None], np.zeros(1))
    d_soft = stiff.damage_on(soft, d)
    assert stiff.damage_on(stiff, d)[0] == pytest.approx(d[0], rel=1e-12)  # onto itself: unchanged
    n = 20001  # reload the soft bond from closed along the same mix (monotonic: one call, each point from d_soft)
    m0s, mfs, _ = (float(x[0]) for x in soft.onset_and_final(one(a), one(b)))
    path = np.linspace(0.0, 1.05 * mfs, n) / np.hypot(a, b)
    tn, ts, dd = soft.tractions(a * path, (b * path)[:, None], np.full(n, d_soft[0]))
    work = float(np.sum(0.5 * ((tn[1:] + tn[:-1]) * a + (ts[1:, 0] + ts[:-1, 0]) * b) * np.diff(path)))
    assert dd[-1] == 1.0
    assert work == pytest.approx((1 - f) * float(soft.toughness(B)), rel=2e-3, abs=1e-3 * GIc)
    assert np.hypot(tn, ts[:, 0]).max() == pytest.approx((1 - f) * stiff.K * m0, rel=2e-3, abs=1e-3 * Z0)


def test_bk_limits_and_compression():
    assert AS4.toughness(0.0) == pytest.approx(969.0) and AS4.toughness(1.0) == pytest.approx(1719.0)
    # compression: the normal penalty stays, no damage from pressure alone
    tn, ts, d = AS4.tractions(np.array([-1e-6]), np.array([[0.0]]), np.zeros(1))
    assert tn[0] == pytest.approx(-1e8) and d[0] == 0.0


def test_damage_is_irreversible_and_unloading_is_secant():
    dn = np.array([1.5 * 80e6 / 1e14])  # past onset
    _, _, d = AS4.tractions(dn, np.zeros((1, 1)), np.zeros(1))
    assert 0 < d[0] < 1
    tn_back, _, d_back = AS4.tractions(0.5 * dn, np.zeros((1, 1)), d)  # unload halfway
    assert d_back[0] == d[0] and tn_back[0] == pytest.approx((1 - d[0]) * 1e14 * 0.5 * dn[0])


def test_bad_parameters_are_refused():
    with pytest.raises(ValueError):
        HashinCohesiveLaw(K=1e10, Z0=80e6, R0=100e6, GIc=1.0, GIIc=2.0)  # Gc below strength^2 / 2K
    with pytest.raises(ValueError):
        HashinCohesiveLaw(K=1e14, Z0=80e6, R0=100e6, GIc=969.0, GIIc=1719.0, mixed_mode="linear")


def test_friction_opposes_slip_and_needs_contact():
    f = friction_traction(np.array([-10e6, 5e6]), np.array([[0.2], [0.2]]), 0.3, 1e-6)
    assert f[0, 0] == pytest.approx(-0.3 * 10e6, rel=1e-6) and f[1, 0] == 0.0


@settings(max_examples=30, deadline=None, derandomize=True)
@given(seed=st.integers(0, 10_000), mode=st.sampled_from(["bk", "power"]))
def test_compiled_law_is_the_reference_law(seed, mode):
    """The per-step kernel (tractions_fast) and the vectorised reference agree to round-off on
    random separations, orientations and damage states, in tension and compression."""
    rng = np.random.default_rng(seed)
    law = HashinCohesiveLaw(K=1e14, Z0=80e6, R0=100e6, GIc=969.0, GIIc=1719.0, eta=2.284, mixed_mode=mode)
    delta = rng.normal(size=(64, 3)) * rng.choice([1e-7, 1e-6, 1e-5], size=(64, 1))
    normal = rng.normal(size=(64, 3))
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    damage = rng.uniform(0, 1, 64) * (rng.uniform(size=64) < 0.5)
    dn = np.einsum("bi,bi->b", delta, normal)
    tn, ts, d = law.tractions(dn, delta - dn[:, None] * normal, damage)
    t, d2 = law.tractions_fast(delta, normal, damage)
    np.testing.assert_allclose(d, d2, rtol=0, atol=1e-12)
    np.testing.assert_allclose(t, tn[:, None] * normal + ts, rtol=1e-12, atol=1e-12 * np.abs(t).max())


class _PointEngine:
    """The two back-end calls LawBonds uses, on plain arrays (positions moved by the test)."""

    def __init__(self, x):
        self.x, self.f = x, np.zeros_like(x)

    def positions_of(self, ids):
        return self.x[ids]

    def add_forces(self, ids, F):
        self.f[ids] += F


@pytest.mark.parametrize("angle", [0.0, 30.0, 90.0])
def test_law_bonds_measure_toughness_and_conserve_momentum(angle):
    """Two particles pulled apart along a fixed direction to full decohesion: the bond forces
    are equal and opposite at every step, and the measured dissipation (work of the bond
    forces minus stored energy) equals Gc(B) x area, B from the separation's mode mix."""
    from physics.law_bonds import LawBonds
    X = np.array([[0.0, 0.0, 0.0], [0.0, 1e-3, 0.0]])
    area = 2.5e-7
    bonds = LawBonds([[0, 1]], X, [[0.0, 1.0, 0.0]], area, AS4)
    e = np.array([np.sin(np.radians(angle)), np.cos(np.radians(angle)), 0.0])  # 0 deg: pure opening
    dn, ds = e[1], e[0]
    m0, mf, B = AS4.onset_and_final(np.array([dn]), np.array([ds]))
    eng = _PointEngine(X.copy())
    for s in np.linspace(0, 1.3 * mf[0], 4000):
        eng.x[1] = X[1] + s * e
        eng.f[:] = 0.0
        bonds.apply(eng, 1e-9)
        np.testing.assert_allclose(eng.f.sum(axis=0), 0.0, atol=1e-12 * max(1.0, np.abs(eng.f).max()))
    assert bonds.failed().all()
    assert bonds.dissipated_energy() == pytest.approx(area * float(AS4.toughness(B)[0]), rel=2e-3)


def test_compiled_bond_kernels_match_numpy():
    """Scatter, Love-Weber bond stress and the Hoffman index: compiled loops = numpy forms."""
    from physics import kernels
    from physics.failure import HoffmanStrengths, hoffman, to_ply_axes
    rng = np.random.default_rng(3)
    n, nb = 12, 40
    loc = np.array([rng.choice(n, 2, replace=False) for _ in range(nb)])
    F, d0 = rng.normal(size=(nb, 3)), rng.normal(size=(nb, 3))
    cell = rng.uniform(1, 2, n)
    f = np.zeros((n, 3))
    np.add.at(f, loc[:, 1], F)
    np.add.at(f, loc[:, 0], -F)
    np.testing.assert_allclose(kernels.scatter_pairs(loc, F, n), f, rtol=1e-14, atol=1e-14)
    dyad = 0.5 * np.einsum("bi,bj->bij", F, d0)
    s = np.zeros((n, 3, 3))
    np.add.at(s, loc[:, 0], dyad)
    np.add.at(s, loc[:, 1], dyad)
    s /= cell[:, None, None]
    sb = 0.5 * (s[loc[:, 0]] + s[loc[:, 1]])
    sb = 0.5 * (sb + np.swapaxes(sb, 1, 2))
    ref = np.stack([sb[:, 0, 0], sb[:, 1, 1], sb[:, 2, 2], sb[:, 1, 2], sb[:, 0, 2], sb[:, 0, 1]], axis=1)
    np.testing.assert_allclose(kernels.bond_stress(loc, F, d0, cell, n), ref, rtol=1e-12, atol=1e-14)
    k = HoffmanStrengths(1.5e9, 1.2e9, 50e6, 200e6, 50e6, 200e6, 60e6, 75e6, 75e6)
    axes = np.array([np.linalg.qr(rng.normal(size=(3, 3)))[0] for _ in range(nb)])
    stress = rng.normal(size=(nb, 6)) * 3e7
    scale = rng.uniform(0.9, 1.0, nb)
    got = kernels.hoffman_ply(stress, axes, scale, (k.Xt, k.Xc, k.Yt, k.Yc, k.Zt, k.Zc, k.S23, k.S13, k.S12))
    np.testing.assert_allclose(got, hoffman(to_ply_axes(stress / scale[:, None], axes), k), rtol=1e-12)


def test_failed_bonds_in_compression_slide_with_friction():
    """A fully failed bond pressed shut and sheared: normal penalty, Coulomb friction mu |t_n|
    against the slip rate, momentum exact."""
    from physics.law_bonds import LawBonds
    X = np.array([[0.0, 0.0, 0.0], [0.0, 1e-3, 0.0], [1e-3, 0.0, 0.0], [1e-3, 1e-3, 0.0]])
    bonds = LawBonds([[0, 1], [2, 3]], X, [[0.0, 1.0, 0.0]] * 2, 1e-6, AS4, friction=0.4)
    bonds.damage[:] = 1.0
    eng = _PointEngine(X.copy())
    bonds.apply(eng, 0.0)
    for k in range(1, 5):
        eng.x[1] = X[1] + [1e-7 * k, -2e-7, 0.0]  # closed, sliding +x; the second pair stays put
        eng.f[:] = 0.0
        bonds.apply(eng, 1e-6)
    tn = -2e-7 * AS4.K
    assert eng.f[1, 1] == pytest.approx(-1e-6 * tn)  # pushed back out
    assert eng.f[1, 0] == pytest.approx(-0.4 * abs(tn) * 1e-6, rel=1e-3)  # friction against the slip
    np.testing.assert_allclose(eng.f[2:], 0.0, atol=0)
    np.testing.assert_allclose(eng.f.sum(axis=0), 0.0, atol=1e-12)


def _interface_row(n=6, h=1e-3):
    """n vertical pairs along x (spacing h), joined by an interface LawBonds with neighbours."""
    from physics.law_bonds import LawBonds
    X = np.array([[c * h, y, 0.0] for c in range(n) for y in (0.0, h)])
    pairs = np.arange(2 * n).reshape(n, 2)
    k = np.arange(n)
    along = np.column_stack([np.where(k > 0, k - 1, -1), np.where(k < n - 1, k + 1, -1)])
    return X, LawBonds(pairs, X, [[0.0, 1.0, 0.0]] * n, h * h, AS4, along=along)


def test_interface_slip_ignores_rotation():
    """A rigid rotation of an interface gives no traction; a uniform shear gives K gamma h."""
    X, bonds = _interface_row()
    c, s_ = np.cos(1e-4), np.sin(1e-4)
    R = np.array([[c, -s_, 0], [s_, c, 0], [0, 0, 1]])
    eng = _PointEngine(X @ R.T)
    bonds.apply(eng, 0.0)
    # tangential forces vanish; normal ones are second order (fixed normals): K A h theta^2
    assert np.abs(eng.f[:, 0]).max() < 1e-6 * AS4.K * 1e-6 * 1e-3 * 1e-4
    assert np.abs(eng.f[:, 1]).max() < 2 * AS4.K * 1e-6 * 1e-3 * 1e-8
    X, bonds = _interface_row()
    gamma = 1e-5
    eng = _PointEngine(X + np.column_stack([gamma * X[:, 1], 0 * X[:, 0], 0 * X[:, 0]]))
    bonds.apply(eng, 0.0)
    np.testing.assert_allclose(bonds.traction[:, 0], AS4.K * gamma * 1e-3, rtol=1e-9)


@settings(max_examples=20, deadline=None, derandomize=True)
@given(seed=st.integers(0, 10_000))
def test_interface_forces_balance_forces_and_moments(seed):
    """Any small deformation: the interface's forces sum to zero and their net moment is of
    second order (small-rotation kinematics), where a shear spring on the raw relative
    translation leaves a first-order moment (it resists rotation)."""
    from physics.law_bonds import LawBonds
    X, bonds = _interface_row()
    x = X + np.random.default_rng(seed).normal(size=X.shape) * [1e-7, 1e-7, 0.0]
    raw = LawBonds(bonds.pairs, X, bonds.normal, 1e-6, AS4)
    moments = []
    for b in (bonds, raw):
        eng = _PointEngine(x)
        b.apply(eng, 0.0)
        np.testing.assert_allclose(eng.f.sum(axis=0), 0.0, atol=1e-12 * np.abs(eng.f).max())
        moments.append(abs(np.cross(x, eng.f).sum(axis=0)[2]))
    assert moments[0] < 1e-2 * moments[1]


def _rotation(theta):
    c, s_ = np.cos(theta), np.sin(theta)
    return np.array([[c, -s_, 0], [s_, c, 0], [0, 0, 1]])


def _central_lattice():
    """A 3 x 3 particle square with axial and diagonal central PlyBondLaw bonds (strong enough
    to stay elastic)."""
    from physics.law_bonds import LawBonds
    from physics.laws import PlyBondLaw
    from physics.failure import HoffmanStrengths
    h = 1e-3
    X = np.array([[i * h, j * h, 0.0] for i in range(3) for j in range(3)])
    pairs = [(a, b) for a in range(9) for b in range(a + 1, 9) if np.linalg.norm(X[a] - X[b]) < 1.5 * h]
    pairs = np.array(pairs)
    big = HoffmanStrengths(*([1e12] * 9))
    law = PlyBondLaw(np.full(len(pairs), 1e14), 100.0, big, np.eye(3))
    return X, LawBonds(pairs, X, X[pairs[:, 1]] - X[pairs[:, 0]], h * h, law, volume=np.full(9, h**3),
                       finite_rotation=True, label="intralaminar")


@pytest.mark.parametrize("which", ["interface", "central"])
def test_finite_rotation_bonds_are_free_of_rigid_motion_and_conservative(which):
    """Corotated kinematics: a rigid rotation of 0.4 rad (plus a translation) gives no force,
    where the fixed-normal split of the same interface pushes with K A h theta^2 / 2; on a
    deformed and turned configuration the forces are minus the gradient of the bonds' stored
    energy (central differences), sum to zero and have no net moment."""
    from physics.law_bonds import LawBonds
    if which == "interface":
        X, small = _interface_row()
        bonds = LawBonds(small.pairs, X, small.normal, small.area, AS4, along=small.along, finite_rotation=True)
    else:
        X, bonds = _central_lattice()
    R = _rotation(0.4)
    eng = _PointEngine(X @ R.T + [3e-4, -1e-4, 0.0])
    bonds.apply(eng, 0.0)
    scale = AS4.K * 1e-6 * 1e-3  # K A h: the force of a unit strain
    assert np.abs(eng.f).max() < 1e-9 * scale
    if which == "interface":
        eng = _PointEngine(X @ R.T)
        small.apply(eng, 0.0)
        assert np.abs(eng.f).max() > 1e-2 * scale * 0.4**2  # what the fixed normal would add
    rng = np.random.default_rng(7)
    x = (X + rng.normal(size=X.shape) * [2e-7, 2e-7, 0.0]) @ R.T
    eng = _PointEngine(x.copy())
    bonds.apply(eng, 0.0)
    f = eng.f.copy()
    np.testing.assert_allclose(f.sum(axis=0), 0.0, atol=1e-12 * np.abs(f).max())
    assert abs(np.cross(x, f).sum(axis=0)[2]) < 1e-9 * np.abs(f).max() * 1e-3
    assert bonds.damage.max() == 0.0  # elastic: the stored energy is the potential
    eps = 1e-11
    for p_ in range(len(x)):
        for k in range(2):
            e = []
            for sgn in (1, -1):
                xp = x.copy()
                xp[p_, k] += sgn * eps
                bonds.evaluate(xp, 0.0)
                e.append(bonds.stored_energy())
            assert f[p_, k] == pytest.approx(-(e[0] - e[1]) / (2 * eps), rel=1e-5, abs=1e-6 * np.abs(f).max())


def test_finite_rotation_matches_small_rotation_when_small():
    """Under a small deformation and a 1e-4 rotation the corotated interface tractions equal
    the small-rotation slip's (to the second order they neglect)."""
    from physics.law_bonds import LawBonds
    X, small = _interface_row()
    big = LawBonds(small.pairs, X, small.normal, small.area, AS4, along=small.along, finite_rotation=True)
    x = (X + np.random.default_rng(1).normal(size=X.shape) * [1e-7, 1e-7, 0.0]) @ _rotation(1e-4).T
    for b in (small, big):
        b.apply(_PointEngine(x.copy()), 0.0)
    np.testing.assert_allclose(big.traction, small.traction, atol=1e-3 * np.abs(small.traction).max())


def test_finite_rotation_is_refused_where_it_is_not_built():
    from physics.law_bonds import LawBonds
    X = np.array([[0.0, 0.0, 0.0], [0.0, 1e-3, 0.0]])
    with pytest.raises(ValueError, match="central law"):
        LawBonds([[0, 1]], X, [[0.0, 1.0, 0.0]], 1e-6, AS4, finite_rotation=True)


@pytest.mark.parametrize("path", ["apply", "apply_reference"])
@settings(max_examples=10, deadline=None, derandomize=True)
@given(friction=st.floats(0.0, 1.0), press=st.floats(1e-8, 1e-6), slip=st.floats(1e-6, 1e-4))
def test_friction_s_work_is_kept_apart_from_the_decohesion(path, friction, press, slip):
    """A bond opened in mode I past decohesion (linear softening: GIc x its area dissipated), then
    pressed shut by ``press`` and slid by ``slip`` (m) at a rate far above the friction's
    regularisation: the decohesion's share stays GIc x area, the friction's is mu |t_n| x slip x
    area, and together they are the bond's whole dissipation (the compiled step and the numpy one)."""
    from physics.law_bonds import LawBonds
    X = np.array([[0.0, 0.0, 0.0], [0.0, 1e-3, 0.0]])
    A = 1e-6
    bonds = LawBonds([[0, 1]], X, [[0.0, 1.0, 0.0]], A, AS4, friction=friction)
    eng, dt = _PointEngine(X.copy()), 1e-8
    step = lambda: (eng.f.fill(0.0), getattr(bonds, path)(eng, dt))
    opening = 1.5 * 2 * AS4.GIc / AS4.Z0  # past the final opening
    for u in np.linspace(0.0, opening, 2001)[1:]:
        eng.x[1] = X[1] + [0.0, u, 0.0]
        step()
    assert bonds.failed().all()
    # shut, a step landing on contact (the trapezoid over a step across it books K u u_prev / 2),
    # and pressed: the contact's penalty stores what it takes
    for u in np.concatenate([np.linspace(opening, 0.0, 101)[1:], np.linspace(0.0, -press, 21)[1:]]):
        eng.x[1] = X[1] + [0.0, u, 0.0]
        step()
    n = 200
    for k in range(1, n + 1):  # slid at slip / (n dt), >= 5e-1 m/s against v_reg 1e-3 m/s
        eng.x[1] = X[1] + [slip * k / n, -press, 0.0]
        step()
    GIc_work = AS4.GIc * A
    assert bonds.decohesion_energy() == pytest.approx(GIc_work, rel=1e-3)
    friction_work = friction * AS4.K * press * slip * A
    assert bonds.friction_work == pytest.approx(friction_work, rel=1e-2, abs=1e-9 * GIc_work)
    assert bonds.dissipated_energy() == pytest.approx(bonds.decohesion_energy() + bonds.friction_work, rel=1e-12)
