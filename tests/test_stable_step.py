"""The assembled stable step (fem_region.stable_step): the largest frequency of elements and the
springs between nodes, against a dense generalized eigensolver (scipy.linalg.eigh on K and M,
an independent computation), against the safe bounds it replaces (Irons' element bound plus
the springs' Gershgorin rows: never a shorter step), and as the stability limit itself: an
undamped paired laminate vibrates at 0.98 of the step and blows up at 1.02 of it."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
from hypothesis import given, settings, strategies as st

from coupling.participants.fem import cohesive_node_bonds, energies_with
from fem_region import materials, mesh
from fem_region.elements import ELEMENTS
from fem_region.explicit import ExplicitDynamics
from fem_region.region import FemRegion
from fem_region.stable_step import DENSE_BELOW, assembled_critical_dt, spring_stiffness
from physics.laws import HashinCohesiveLaw


def layered(element: str, n_along: int, n_through: int, E: float, ratio: float, rho: float, split: bool):
    """A two-layer strip 4 x 1 mm (x 1 mm in 3D), the upper layer E / ratio; with split, its
    interface nodes doubled (mesh.split_interfaces) and returned as pairs (else none)."""
    dim = 3 if element in ("hex8", "tet4") else 2
    x, z = np.linspace(0, 4e-3, n_along + 1), np.linspace(0, 1e-3, 2 * n_through + 1)
    m = mesh.rectangle(x, z, element) if dim == 2 else mesh.box(x, np.linspace(0, 1e-3, 3), z, element)
    centre = m.p[:, m.t].mean(axis=1)
    upper = centre[dim - 1] > 0.5e-3
    pairs = np.zeros((0, 2), int)
    if split:
        P, T, pairs = mesh.split_interfaces(m.p, m.t, upper.astype(int), [0.5e-3], dim - 1, 1e-12)
        m = type(m)(P, T)
    iso = materials.isotropic(E, 0.3)
    D = materials.reduce(iso, dim, "plane_stress") if dim == 2 else iso
    D = np.where(upper[:, None, None], D / ratio, D)
    return FemRegion(m, ELEMENTS[element], D, rho, 1e-3 if dim == 2 else 1.0), pairs


def law(K: float) -> HashinCohesiveLaw:
    """Strengths far above what the tests load: the elastic branch throughout."""
    return HashinCohesiveLaw(K=K, Z0=1e12, R0=1e12, GIc=1e12, GIIc=1e12)


def dense_dt(K, m: np.ndarray, dim: int) -> float:
    """2 / omega_max by LAPACK's generalized symmetric solver on K and the diagonal mass matrix."""
    lam = scipy.linalg.eigh(K.toarray(), np.diag(np.repeat(m, dim)), eigvals_only=True)
    return 2.0 / np.sqrt(lam[-1])


@settings(max_examples=12, deadline=None)
@given(element=st.sampled_from(["quad4", "tri3", "hex8", "tet4"]), n_along=st.integers(2, 26),
       n_through=st.integers(1, 3), E=st.floats(1e9, 2e11), ratio=st.floats(0.1, 10.0),
       rho=st.floats(500.0, 8000.0), penalty=st.floats(0.01, 100.0))
def test_the_assembled_step_is_the_largest_frequency_and_never_below_the_bounds(element, n_along, n_through, E,
                                                                                ratio, rho, penalty):
    """Elements of two stiffnesses, their interface nodes doubled and joined by pairs of a
    penalty drawn around the elements' own (E / h, 0.01-100 x): the step equals the dense
    solver's to 1e-8, on both the dense and the Lanczos path, and is never shorter than the
    bound the far field used before (omega^2 <= omega_el^2 + 4 k / m_lighter)."""
    r, pairs = layered(element, n_along, n_through, E, ratio, rho, split=True)
    dyn = ExplicitDynamics(r)
    area = np.full(len(pairs), 4e-6 / len(pairs))  # the plane's (4 x 1 mm) share
    k = penalty * E / 0.5e-3 * area
    dyn.add_springs(spring_stiffness(r.n_nodes, r.dim, pairs, np.tile([1.0, -1.0], (len(pairs), 1)), k))
    dt = dyn.critical_dt()
    assert dt == pytest.approx(dense_dt(r.K + dyn.springs, dyn.m, r.dim), rel=1e-8)
    m_pair = np.minimum(dyn.m[pairs[:, 0]], dyn.m[pairs[:, 1]])
    bound = 2.0 / np.sqrt((2.0 / r.critical_dt()) ** 2 + np.max(4 * k / m_pair))
    assert dt >= bound * (1 - 1e-12)


def test_both_paths_of_the_solver_are_exercised():
    """The hypothesis draws above reach both the dense path and ARPACK's (the DOF counts)."""
    small, _ = layered("quad4", 2, 1, 1e10, 1.0, 1e3, split=False)
    large, _ = layered("hex8", 26, 3, 1e10, 1.0, 1e3, split=False)
    assert small.ndof < DENSE_BELOW < large.ndof
    for r in (small, large):
        assert assembled_critical_dt(r.K, r.mass, r.dim) == pytest.approx(dense_dt(r.K, r.mass, r.dim), rel=1e-8)


def vibrate(element: str, share: float, steps: int) -> float:
    """A two-layer strip, its interface joined by cohesive pairs at a penalty whose pairs are
    as stiff as the elements (10 E / h), undamped, set bending and shearing the interface by a
    smooth velocity field (the fastest modes hold only round-off: above the limit they grow
    from it); run at ``share`` of the stable step; returns the largest |energy change| / the
    start's over ``steps`` (stopped once above 1e3)."""
    r, pairs = layered(element, 12, 2, 7e10, 3.0, 2700.0, split=True)
    dyn = ExplicitDynamics(r)
    area = np.full(len(pairs), 4e-6 / len(pairs))  # the plane's (4 x 1 mm) share
    bonds = cohesive_node_bonds(dyn, pairs, area, law(10 * 7e10 / 1e-3), 0.0)
    dyn.spring_dt_limit = np.inf  # the step of the assembled model alone (intact pairs: no damper acts)
    energies = energies_with(dyn.energies, [bonds])
    X, v = r.X, np.zeros_like(r.X)
    v[:, 0] = 0.3 * np.sin(np.pi * X[:, 0] / 4e-3) * np.sign(X[:, -1] - 0.5e-3)
    v[:, -1] = np.cos(np.pi * X[:, 0] / 4e-3)
    dyn.set_initial_velocity(v)
    dt = share * dyn.critical_dt()
    dyn.start()
    e0 = energies()["kinetic"]
    worst = 0.0
    for _ in range(steps):
        dyn.kick_drift(dt)
        dyn.compute_forces()
        dyn.kick(dt)
        e = energies()
        worst = max(worst, abs(e["kinetic"] + e["internal"] - e0) / e0)
        if worst > 1e3:
            break
    return worst


@pytest.mark.parametrize("element", ["quad4", "hex8"])
def test_the_step_is_the_stability_limit(element):
    """Central differences are stable below 2 / omega_max and not above it: the paired strip's
    energy holds within 5 % over 3,000 steps at 0.98 of the step, and grows a thousandfold
    within 600 steps at 1.02 of it (its fastest mode by 1.49 x a step). A step shorter than the
    true limit (a bound) would hold at 1.02 too."""
    assert vibrate(element, 0.98, 3000) <= 0.05
    assert vibrate(element, 1.02, 600) > 1e3
