"""The dampers of the FEM's cohesive pairs (participants.fem.pair_damping, LawBonds.damping).

A softened pair is a bilinear spring: K in compression, (1 - d) K in opening. Under central
differences such a spring rings at steps well inside the linear limit 2 / omega (resonance
tongues of the piecewise-linear map): the mechanism the dampers are for. Checked on one pair
of point masses, its relative motion a single degree of freedom with omega^2 = K A / mu:
undamped it grows a millionfold at points inside the limit; with the dampers (10 % of the
pair's critical damping on the opening's rate, on softened pairs at contact) it decays at every
step up to omega dt = 1.45 (the far field keeps its pairs below PAIR_RING_LIMIT = 1.5; a scan
rings from 1.54, benchmarks/pair_ringing.py) and every softening, and the damper books the
energy it takes. The dampers act on the opening only, only at contact, and only on pairs that
have softened and not failed.
"""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from coupling.participants.fem import PAIR_RING_LIMIT, pair_damping, pair_step_limit
from physics.law_bonds import LawBonds
from physics.laws import HashinCohesiveLaw

K, A, M = 1e14, 1e-8, 1e-9  # Pa/m, m^2, kg (each of the two masses)
MU = M / 2  # kg, their reduced mass
OMEGA = np.sqrt(K * A / MU)  # rad/s, the pair's own mode


def pair(damage: float, damped: bool, strong: bool = True) -> LawBonds:
    """One bond along y between two masses 0.1 mm apart, its damage set; ``strong``: strengths
    and toughness so high that the damage stays where it was set (the spring stays bilinear)."""
    law = HashinCohesiveLaw(K=K, Z0=1e12, R0=1e12, GIc=1e12, GIIc=1e12) if strong else \
        HashinCohesiveLaw(K=K, Z0=40e6, R0=20e6, GIc=100.0, GIIc=300.0)
    b = LawBonds(np.array([[0, 1]]), np.array([[0.0, 0.0, 0.0], [0.0, 1e-4, 0.0]]), np.array([[0.0, 1.0, 0.0]]),
                 A, law, damping=pair_damping(K, A, MU) if damped else None)
    b.damage[:] = damage
    return b


def ring(wdt: float, damage: float, damped: bool, steps: int, v0: float = 1.0, u0: float = 1e-9):
    """Velocity Verlet on the pair from opening u0 (m) and relative velocity 2 v0 (m/s) along
    the bond, at omega dt = wdt; returns (largest energy / start, final energy / start, the
    start's energy J, the dampers' booked work J). Energy: kinetic at whole steps and the
    bilinear spring's."""
    b = pair(damage, damped)
    x, v = b.X.copy(), np.zeros((2, 3))
    x[1, 1] += u0
    v[0, 1], v[1, 1] = -v0, v0
    dt = wdt / OMEGA
    f = np.zeros((2, 3))

    def forces(step):
        F = b.evaluate(x, step)[0]
        f[1], f[0] = F, -F

    def energy():
        dn = b.delta[0, 1]
        return 0.5 * M * np.sum(v**2) + 0.5 * K * A * ((1 - b.damage[0]) * max(dn, 0.0) ** 2 + min(dn, 0.0) ** 2)

    forces(0.0)
    e0 = energy()
    worst = 1.0
    for _ in range(steps):
        v += 0.5 * dt * f / M
        x += dt * v
        forces(dt)
        v += 0.5 * dt * f / M
        worst = max(worst, energy() / e0)
        if worst > 1e6:
            break
    return worst, energy() / e0, e0, b.damping_work


@pytest.mark.parametrize("wdt, damage", [(1.6, 0.4), (1.8, 0.95)])
def test_a_softened_pair_rings_undamped_inside_its_linear_limit(wdt, damage):
    """The mechanism: undamped, a softened pair grows a millionfold at 0.8 and 0.9 of its linear
    limit (omega dt = 2), where an intact one (the same spring both ways) holds."""
    assert ring(wdt, damage, False, 5000)[0] > 1e6
    assert ring(wdt, 0.0, False, 5000)[0] < 10


@settings(max_examples=25, deadline=None)
@given(wdt=st.floats(0.05, 1.45), damage=st.floats(0.01, 0.99), v0=st.floats(-1.0, 1.0),
       u0=st.floats(-1e-8, 1e-8))
def test_a_damped_pair_decays_at_every_step_and_softening(wdt, damage, v0, u0):
    """Damped, a softened pair's energy never grows past the whole-step measure's own swing
    (100 x, where the undamped tongues reach 1e6) and is gone (1e-6 of its start) within 5,000
    steps, at any omega dt up to 1.45 (the far field keeps below PAIR_RING_LIMIT, 1.5) and
    any softening."""
    if abs(v0) < 1e-3 and abs(u0) < 1e-11:
        v0 = 1.0
    worst, final, _, _ = ring(wdt, damage, True, 5000, v0, u0)
    assert worst < 100
    assert final < 1e-6


def test_the_far_field_keeps_its_pairs_inside_the_ring_limit():
    """pair_step_limit is PAIR_RING_LIMIT / omega_p of the stiffest pair (an independent
    omega_p: sqrt(2 K A / m) for equal masses m)."""
    area, m = np.array([1e-8, 4e-8, 2e-8]), np.array([1e-9, 1e-9, 3e-9])
    omega = np.sqrt(2 * K * area / m)
    assert pair_step_limit(K, area, m / 2) == pytest.approx(PAIR_RING_LIMIT / omega.max(), rel=1e-12)


def test_the_damper_books_the_energy_it_takes():
    """At steps small against the pair's period the damper's booked work is the energy the
    ringing lost (to 2 %); the bond's ledger (work - stored) holds it as dissipation."""
    for damage in (0.05, 0.5, 0.95):
        worst, final, e0, work = ring(0.05, damage, True, 40000)
        assert final < 1e-6
        assert work == pytest.approx(e0, rel=0.02)


def test_the_damper_acts_on_softened_pairs_at_contact_on_their_opening_only():
    """Closing at 1 m/s into contact, a softened pair takes c rate more than its spring; a pure
    slip, a rigid motion, an opening pair (not at contact), an intact pair and a failed one
    take no damper force at all."""
    dt, u = 1e-9, 1e-9
    c = float(pair_damping(K, A, MU))

    def force(damage, start, move):
        b = pair(damage, True)
        x = b.X.copy()
        x[1] += start
        b.evaluate(x, 0.0)
        F = b.evaluate(x + np.vstack([np.zeros(3), move]), dt)[0]
        dn = b.delta[0, 1]
        spring = (1 - damage) * K * A * dn if dn > 0 else K * A * dn  # on the second mass: -A t
        return F, -spring

    F, spring = force(0.5, [0, 0, 0], [0, -u, 0])  # closing into contact at 1 m/s
    assert F[1] == pytest.approx(spring + A * c * 1.0, rel=1e-9)
    F, spring = force(0.5, [0, -2 * u, 0], [0, u, 0])  # opening, still in contact: the damper resists
    assert F[1] == pytest.approx(spring - A * c * 1.0, rel=1e-9)
    for damage, start, move in ((0.5, [0, 0, 0], [u, 0, 0]),  # slip: the shear spring alone
                                (0.5, [0, 2 * u, 0], [0, u, 0]),  # opening, apart
                                (0.0, [0, 0, 0], [0, -u, 0]),  # intact: a linear spring
                                (0.5, [0, 0, 0], [0, 0, 0])):  # at rest
        F, spring = force(damage, start, move)
        slip = np.array([-(1 - damage) * K * A * (start[0] + move[0]), 0.0, 0.0])
        assert F == pytest.approx(slip + np.array([0.0, spring, 0.0]), rel=1e-9, abs=1e-30)
    b = pair(1.0, True)  # failed, open
    b.evaluate(b.X, 0.0)
    x = b.X.copy()
    x[1, 1] += 1e-7
    assert np.all(b.evaluate(x, dt)[0] == 0.0)
    b = pair(0.5, True)  # a rigid motion
    b.evaluate(b.X, 0.0)
    assert np.all(b.evaluate(b.X + np.array([1e-9, -2e-9, 1e-9]), dt)[0] == 0.0)


def test_the_reference_step_equals_the_fused_one_with_dampers():
    """LawBonds.evaluate_reference (numpy) and the fused kernel agree on a damped, softening
    pair family, forces and booked damper work."""
    rng = np.random.default_rng(3)
    n = 40
    X = np.column_stack([np.repeat(np.arange(n) * 1e-4, 2), np.tile([0.0, 1e-4], n), np.zeros(2 * n)])
    pairs = np.arange(2 * n).reshape(n, 2)
    law = HashinCohesiveLaw(K=K, Z0=40e6, R0=20e6, GIc=100.0, GIIc=300.0)
    make = lambda: LawBonds(pairs, X, np.tile([0.0, 1.0, 0.0], (n, 1)), A, law,
                            damping=pair_damping(K, A, np.full(n, MU)))
    a, b = make(), make()
    x = X.copy()
    for _ in range(200):
        x = x + 2e-8 * rng.normal(size=x.shape)
        Fa = a.evaluate_reference(x[a.ids], 1e-9).copy()
        Fb = b.evaluate(x[b.ids], 1e-9)
        np.testing.assert_allclose(Fb, Fa, rtol=1e-12, atol=1e-300)
    assert a.damage.max() > 0  # the draw softened some
    assert b.damping_work == pytest.approx(a.damping_work, rel=1e-10)
    assert a.damping_work > 0
