"""Node-to-face interfaces (fem_region.node_to_face, participants.fem.node_to_face_bonds): two
blocks meshed independently and joined across their common plane by the interlaminar law.
Checked against their own geometry: the points reproduce every affine field (so a rigid motion of
any size gives no force), a uniform opening and slip give each slave its tributary area times
K delta, forces sum to zero, and an undamped vibration keeps its energy at the stable step of
elements and bonds assembled."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from coupling.participants.fem import cohesive_penalty, energies_with, face_pair_mass, node_to_face_bonds
from fem_region import materials, mesh
from fem_region.elements import ELEMENTS
from fem_region.explicit import ExplicitDynamics
from fem_region.node_to_face import node_to_face
from fem_region.region import FemRegion
from physics.laws import HashinCohesiveLaw

H = 1e-3  # m, each block's thickness
ELEMENT_OF = {2: {"quad4": "quad4", "tri3": "tri3"}, 3: {"hex8": "hex8", "tet4": "tet4"}}


def blocks(element: str, n_lower: tuple, n_upper: tuple, L: float = 4e-3, W: float = 3e-3):
    """Two blocks [0, L] x ([0, W] x) of thickness H stacked along the last axis, n elements
    along each in-plane axis (lower, upper: tuples of counts), 2 through each block; returns
    (mesh, lower elements, upper elements, axis)."""
    dim = len(n_lower) + 1
    lo = [np.linspace(0, s, k + 1) for s, k in zip((L, W), n_lower)]
    up = [np.linspace(0, s, k + 1) for s, k in zip((L, W), n_upper)]
    make = mesh.rectangle if dim == 2 else mesh.box
    m, (lower, upper) = mesh.joined(make(*lo, np.linspace(0, H, 3), element),
                                    make(*up, np.linspace(H, 2 * H, 3), element))
    return m, lower, upper, dim - 1


def region(m, element: str) -> FemRegion:
    e = ELEMENTS[element]
    D = materials.reduce(materials.isotropic(5e9, 0.3), e.dim, "plane_stress") if e.dim == 2 \
        else materials.isotropic(5e9, 0.3)
    return FemRegion(m, e, D, 1500.0, 1.0 if e.dim == 3 else 2e-3)


def law(K: float) -> HashinCohesiveLaw:
    """Strengths far above what the tests load: the elastic branch throughout."""
    return HashinCohesiveLaw(K=K, Z0=1e9, R0=1e9, GIc=1e9, GIIc=1e9, eta=2.0, mixed_mode="bk")


meshes = st.one_of(
    st.tuples(st.sampled_from(["quad4", "tri3"]), st.tuples(st.integers(2, 9)), st.tuples(st.integers(2, 9))),
    st.tuples(st.sampled_from(["hex8", "tet4"]), st.tuples(st.integers(1, 4), st.integers(1, 4)),
              st.tuples(st.integers(1, 4), st.integers(1, 4))))


def joined_dynamics(element, n_lower, n_upper, K=1e14):
    m, lower, upper, axis = blocks(element, n_lower, n_upper)
    r = region(m, element)
    face = node_to_face(m.p, m.t, lower, upper, axis, H, 1e-9)
    dyn = ExplicitDynamics(r)
    bonds = node_to_face_bonds(dyn, face, face.area, law(K), 0.0)
    return dyn, face, bonds


def node_forces(dyn) -> np.ndarray:
    return sum(model() for model in dyn.node_forces)[:, : dyn.region.dim]


@settings(max_examples=25, deadline=None, derandomize=True)
@given(meshes, st.floats(-np.pi, np.pi), st.floats(-1e-3, 1e-3))
def test_a_rigid_motion_of_any_size_gives_no_force(spec, angle, shift):
    """The points follow their faces' nodes by the shape functions, which reproduce affine
    fields: a node and its point move together under any rotation and translation."""
    dyn, face, bonds = joined_dynamics(*spec)
    X = dyn.region.X
    c, s = np.cos(angle), np.sin(angle)
    R = np.array([[c, -s], [s, c]]) if X.shape[1] == 2 else np.array([[c, 0, -s], [0, 1, 0], [s, 0, c]])
    dyn.state.u[:] = X @ R.T + shift - X
    f = node_forces(dyn)
    assert np.abs(f).max() <= 1e-9 * bonds.law.K * face.area.max() * np.abs(X).max()
    assert np.abs(bonds.delta).max() <= 1e-12


@settings(max_examples=25, deadline=None, derandomize=True)
@given(meshes, st.floats(-1e-7, 1e-7), st.floats(-1e-7, 1e-7))
def test_a_uniform_opening_and_slip_load_each_slave_by_its_area(spec, opening, slip):
    """Upper block moved by a uniform jump (slip along x, opening along the normal): every
    slave takes K A_s delta (A_s its tributary area; the areas tile the plane), the face nodes
    the opposite total, and the forces sum to zero."""
    dyn, face, bonds = joined_dynamics(*spec)
    X, dim = dyn.region.X, dyn.region.dim
    jump = np.zeros(dim)
    jump[0], jump[dim - 1] = slip, opening
    upper = X[:, dim - 1] > H * (1 + 1e-9) - 1e-12
    above = bool(face.slave_above[0])
    assert np.all(face.slave_above == above)  # one plane, one slave side
    upper[face.slave] = above  # the slaves of the plane go with their own block
    upper |= np.isin(np.arange(len(X)), np.unique(face.nodes)) & (not above)
    dyn.state.u[upper] = jump
    f = node_forces(dyn)
    K = bonds.law.K
    # the plane's area: L (2D, per unit thickness of the slice) or L W
    plane = 4e-3 if dim == 2 else 4e-3 * 3e-3
    assert face.area.sum() == pytest.approx(plane, rel=1e-12)
    sign = 1.0 if above else -1.0  # the slave's jump relative to its point
    np.testing.assert_allclose(f[face.slave], -sign * K * face.area[:, None] * jump, rtol=1e-9,
                               atol=1e-9 * K * face.area.max() * max(abs(opening), abs(slip), 1e-12))
    np.testing.assert_allclose(f.sum(axis=0), 0.0, atol=1e-9 * K * plane * max(abs(opening), abs(slip), 1e-12))


def vibrate(r, face, share: float, duration: float) -> tuple[float, float, float]:
    """Both blocks of ``r`` joined by ``face`` start with a velocity field that strains the
    interface, the penalty at the elements' limit (cohesive_penalty with face_pair_mass), and
    run for ``duration`` (in stable steps) at ``share`` of the stable step (intact bonds: their
    dampers never act); (largest |energy change| / start, the bonds' dissipation / start, the
    stable step / the elements' own)."""
    dyn = ExplicitDynamics(r)
    K = cohesive_penalty(dyn, None, face.area, 1e20, face_pair_mass(dyn, face))
    bonds = node_to_face_bonds(dyn, face, face.area, law(K), 0.0)
    X = r.X
    v = np.zeros_like(X)
    v[:, 0] = 0.3 * np.sin(np.pi * X[:, 0] / 4e-3) * np.sign(X[:, -1] - H + 1e-12)
    v[:, -1] = 0.2 * np.cos(np.pi * X[:, 0] / 4e-3)
    dyn.set_initial_velocity(v)
    energies = energies_with(dyn.energies, [bonds])
    dt = share * dyn.critical_dt()
    dyn.start()
    e0 = sum(energies()[k] for k in ("kinetic", "internal"))
    worst = 0.0
    for _ in range(int(round(duration / share))):
        dyn.kick_drift(dt)
        dyn.compute_forces()
        dyn.kick(dt)
        e = energies()
        worst = max(worst, abs(e["kinetic"] + e["internal"] - e0))
    return worst / e0, bonds.dissipated_energy() / e0, dyn.critical_dt() / ExplicitDynamics(r).critical_dt()


@pytest.mark.parametrize("element, n_lower, n_upper", [("quad4", (7,), (4,)), ("tri3", (3,), (8,)),
                                                       ("hex8", (3, 2), (4, 3)), ("tet4", (2, 2), (3, 1))])
def test_an_undamped_vibration_keeps_its_energy_and_is_stable_at_the_bound_step(element, n_lower, n_upper):
    """The energy error of velocity Verlet falls as dt^2 when the forces are the gradient of
    the energy: over 150 stable steps, a quarter and an eighth of the step give errors 4 x
    apart (a force that is not the gradient would leave a drift that does not fall so). At
    0.98 of the step (elements and bonds assembled: fem_region.stable_step) the energy stays
    within 10 % over 6000 steps (the fastest modes' energy measured at whole steps swings
    near the limit, bounded: 6.0 % at 3,000 steps and 6.4 % at 24,000 on the quad4 blocks);
    at 1.02 of it the energy grows past 1e3 x: the step is the limit itself. No energy is
    dissipated."""
    m, lower, upper, axis = blocks(element, n_lower, n_upper)
    r = region(m, element)
    face = node_to_face(m.p, m.t, lower, upper, axis, H, 1e-9)
    coarse, lost, step = vibrate(r, face, 0.25, 150)
    fine, _, _ = vibrate(r, face, 0.125, 150)
    assert step < 1.0  # the bonds lower the step: they are stiff enough to matter
    assert 3.4 <= coarse / fine <= 4.6
    assert coarse <= 5e-3
    assert abs(lost) <= 1e-6
    assert vibrate(r, face, 0.98, 6000)[0] <= 0.1
    assert vibrate(r, face, 1.02, 600)[0] > 1e3
