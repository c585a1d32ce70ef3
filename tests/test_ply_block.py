"""The 3D ply lattice: its stiffness tensor, fracture energies and masses from the bonds it
builds (not from the calibration's own formula), and rotation-free interface slip in 3D."""
import numpy as np
import pytest

from dem_region import ply_block
from physics.law_bonds import LawBonds
from dem_region.ply_lattice import PlyMaterial
from physics.failure import HoffmanStrengths

S = HoffmanStrengths(Xt=1.5e9, Xc=1.2e9, Yt=50e6, Yc=200e6, Zt=50e6, Zc=200e6, S23=60e6, S13=75e6, S12=75e6)
PLY = PlyMaterial(152.4e9, 10.3e9, 4.226e9, 3.7e9, 1550.0, S, 40e3, 300.0)
D = 1e-3


def block(nx=5, ny=4, rows=(3, 3), half_planes=()):
    return ply_block.build((0.0, 0.0, 0.0), (nx, ny), list(rows), [0.0, 90.0], D, PLY, half_planes=half_planes)


def cell_stiffness(b, particle):
    """(6, 6) Voigt Pa of the bonds that start at an interior ``particle``: one cell's share,
    C_ijkl = sum k L^2 n_i n_j n_k n_l / d^3."""
    own = b.intra_pairs[:, 0] == particle
    l = b.x[b.intra_pairs[own, 1]] - b.x[particle]
    k = b.intra_law.K[own] * b.intra_area[own]
    L = np.linalg.norm(l, axis=1)
    n = l / L[:, None]
    voigt = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))
    C = np.zeros((6, 6))
    for a, (i, j) in enumerate(voigt):
        for c, (m, q) in enumerate(voigt):
            C[a, c] = np.sum(k * L**2 * n[:, i] * n[:, j] * n[:, m] * n[:, q]) / D**3
    return C


@pytest.mark.parametrize("angle", [0.0, 90.0])
def test_lattice_has_the_ply_moduli(angle):
    """Uniaxial moduli 1 / S_ii equal the ply's E_x, E_y, E_z and the shear moduli its G,
    summed from the bonds of an interior particle of each ply."""
    b = block(nx=5, ny=5, rows=(3, 3))
    ply = 0 if angle == 0 else 1
    centre = np.flatnonzero((b.index[:, 0] == 2) & (b.index[:, 1] == 2) & (b.index[:, 2] == 3 * ply + 1))[0]
    C = cell_stiffness(b, centre)
    E, G = ply_block.engineering(PLY, angle)
    np.testing.assert_allclose(1.0 / np.diag(np.linalg.inv(C))[:3], E, rtol=1e-9)
    np.testing.assert_allclose(np.diag(C)[3:], G, rtol=1e-12)


def test_too_stiff_shear_is_refused():
    with pytest.raises(ValueError, match="shear moduli too large"):
        ply_block.calibrate(np.array([10e9, 10e9, 10e9]), np.array([9e9, 9e9, 9e9]))


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_a_crack_plane_dissipates_the_ply_energy(axis):
    """Through one cell face normal to x, y or z inside a ply, the bonds that cross it (the
    axial bond through its centre, half of each of the eight diagonals through its edges)
    carry Gf_fibre across the fibres (x in the 0 ply) and Gf_matrix otherwise, per face area."""
    b = block(nx=6, ny=6, rows=(4, 4))
    centre = np.array([2.0, 2.0, 1.5]) * D
    centre[axis] = 2.0 * D if axis == 2 else 2.5 * D
    pts = 0.5 * (b.x[b.intra_pairs[:, 0]] + b.x[b.intra_pairs[:, 1]])
    xi, xj = b.x[b.intra_pairs[:, 0], axis], b.x[b.intra_pairs[:, 1], axis]
    cut = (np.minimum(xi, xj) < centre[axis]) & (np.maximum(xi, xj) > centre[axis])
    r = np.linalg.norm(pts - centre, axis=1)
    axial, diag = cut & (r < 1e-9 * D), cut & (np.abs(r - 0.5 * D) < 1e-9 * D)
    assert axial.sum() == 1 and diag.sum() == 8
    area = b.intra_area
    per_face = (b.intra_law.Gf[axial, axis] @ area[axial] + 0.5 * b.intra_law.Gf[diag, axis] @ area[diag]) / D**2
    assert per_face == pytest.approx(PLY.Gf_fibre if axis == 0 else PLY.Gf_matrix, rel=1e-12)


def test_half_planes_keep_the_mass_and_areas():
    """Symmetry / tie planes on four sides: the particles' mass is rho x the block's volume
    between those planes, and the interface bonds' areas sum to its plan area."""
    nx, ny = 5, 4
    b = block(nx, ny, half_planes=[(0, 0), (1, 0), (0, nx - 1), (1, ny - 1)])
    sphere = 4.0 / 3.0 * np.pi * b.radius**3
    volume = (nx - 1) * D * (ny - 1) * D * 6 * D
    assert np.sum(b.density * sphere) == pytest.approx(PLY.rho * volume, rel=1e-12)
    assert b.inter_area.sum() == pytest.approx((nx - 1) * (ny - 1) * D**2, rel=1e-12)


def test_interface_slip_in_3d_ignores_rotation():
    """A small rigid rotation about x or y of a two-ply block: the interface bonds' slip,
    with the neighbours along both in-plane directions, is of second order; the raw relative
    translation is first order (d theta)."""
    b = block(nx=5, ny=5)
    law = ply_block.interlaminar_law(b, 40e6, 40e6, 500.0, 1000.0)
    theta = 1e-5
    for R in (np.array([[1, 0, 0], [0, np.cos(theta), -np.sin(theta)], [0, np.sin(theta), np.cos(theta)]]),
              np.array([[np.cos(theta), 0, np.sin(theta)], [0, 1, 0], [-np.sin(theta), 0, np.cos(theta)]])):
        x = b.x @ R.T
        slips = []
        for along in (b.inter_along, None):
            bonds = LawBonds(b.inter_pairs, b.x, [[0.0, 0.0, 1.0]] * len(b.inter_pairs), b.inter_area, law,
                             along=along)
            bonds.evaluate(x[bonds.ids], 0.0)
            slips.append(np.abs(bonds.split(bonds.delta)[1]).max())
        assert slips[1] == pytest.approx(D * theta, rel=1e-3)
        assert slips[0] < 1e-4 * slips[1]
