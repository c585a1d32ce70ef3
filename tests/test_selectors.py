"""Zones as selectors (issue #23): a plate's particle column of any footprint (box, cylinder, a
cylinder about the impactor), carved from the cubic ply lattice so that its bonds still tile
the selected volume, the FEM around it exactly the rest of the plate, and a flat-faced rod
(a 3D flat punch) pressing with its whole face."""
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from conftest import assert_checks
from dem_region import ply_block
from test_ply_block import PLY

ROOT = Path(__file__).resolve().parents[1]
PUNCH = ROOT / "tests" / "studies" / "punched_plate.toml"
PLATE = ROOT / "tests" / "studies" / "clamped_plate.toml"
D = 1e-3
ENGINES = ["liggghts", "lammps", "yade"]


def test_carving_the_whole_square_is_the_half_planes_block():
    """Every cell of [0, w]^2 selected: the carved block is the block built with half cells on
    its four side planes, array for array (the box zone is unchanged)."""
    n = 6
    half = ply_block.build((0.0, 0.0, 0.0), (n, n), [2, 3], [0.0, 90.0], D, PLY,
                           half_planes=[(0, 0), (1, 0), (0, n - 1), (1, n - 1)])
    cells = np.zeros((n + 1, n + 1), bool)
    cells[1:n, 1:n] = True
    full = ply_block.build((0.0, 0.0, 0.0), (n, n), [2, 3], [0.0, 90.0], D, PLY)
    carved, kept = ply_block.carve(full, cells)
    assert np.array_equal(kept, np.arange(full.n))
    for name in ("x", "density", "volume", "intra_pairs", "intra_area", "inter_pairs", "inter_area", "inter_along"):
        assert np.array_equal(getattr(carved, name), getattr(half, name)), name
    assert np.array_equal(carved.intra_law.K, half.intra_law.K) and np.array_equal(carved.intra_law.Gf, half.intra_law.Gf)


@settings(max_examples=25, deadline=None)
@given(inner=hnp.arrays(bool, (5, 4)), rows=st.integers(2, 4))
def test_a_carved_block_tiles_its_selected_cells(inner, rows):
    """Any selection of the cells between the block's columns (not only the selectors' shapes): the particles' volumes sum to the
    selected cells' area times the thickness, and for every bond direction the bonds' areas
    sum to d^2 x the selected cells x the rows the direction spans (nz, or nz - 1 across rows):
    the energy of a uniform strain is the continuum's over the selected volume. The kept
    particles are exactly those touching a selected cell, every bond's share is positive."""
    cells = np.pad(inner, 1)  # the cells between the block's columns (those beyond lie outside)
    nx, ny = cells.shape[0] - 1, cells.shape[1] - 1
    full = ply_block.build((0.0, 0.0, 0.0), (nx, ny), [rows], [0.0], D, PLY)
    carved, kept = ply_block.carve(full, cells)
    n_cells = cells.sum()
    assert carved.volume.sum() == pytest.approx(n_cells * D**2 * rows * D, rel=1e-12, abs=1e-30)
    i, j = full.index[:, 0], full.index[:, 1]
    touching = cells[i, j] | cells[i + 1, j] | cells[i, j + 1] | cells[i + 1, j + 1]
    assert np.array_equal(kept, np.flatnonzero(touching))
    offset = carved.index[carved.intra_pairs[:, 1]] - carved.index[carved.intra_pairs[:, 0]]
    assert np.all(carved.intra_area > 0)
    for o in {tuple(r) for r in full.index[full.intra_pairs[:, 1]] - full.index[full.intra_pairs[:, 0]]}:
        on = np.all(offset == o, axis=1)
        expected = D**2 * n_cells * (rows - abs(o[2]))
        assert carved.intra_area[on].sum() == pytest.approx(expected, rel=1e-12, abs=1e-30), o
    assert np.allclose(carved.density * 4 / 3 * np.pi * carved.radius**3, PLY.rho * carved.volume, rtol=1e-12)


@settings(max_examples=10, deadline=None)
@given(inner=hnp.arrays(bool, (4, 4)))
def test_the_carved_interface_pairs_know_their_neighbours(inner):
    """Across a ply interface: the pairs' areas sum to d^2 x the selected cells, and each pair's
    -x, +x, -y, +y neighbour is the kept pair one column over (or -1)."""
    cells = np.pad(inner, 1)
    full = ply_block.build((0.0, 0.0, 0.0), (5, 5), [2, 2], [0.0, 90.0], D, PLY)
    carved, _ = ply_block.carve(full, cells)
    assert carved.inter_area.sum() == pytest.approx(D**2 * cells.sum(), rel=1e-12, abs=1e-30)
    ij = carved.index[carved.inter_pairs[:, 0], :2]
    where = {tuple(r): m for m, r in enumerate(ij.tolist())}
    for m, r in enumerate(ij.tolist()):
        for col, (di, dj) in enumerate(((-1, 0), (1, 0), (0, -1), (0, 1))):
            assert carved.inter_along[m, col] == where.get((r[0] + di, r[1] + dj), -1)


def _plate(path, mode, **overrides):
    from coupling.case import load_case
    from coupling.study.assemble import body_of
    case = load_case(str(path), overrides)
    return case, case.parameters, body_of(case.parameters, mode)


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(shape=st.sampled_from(["box", "cylinder", "impactor"]), spacings=st.integers(5, 12),
       elements=st.sampled_from([1, 2, 3, 5]), margin=st.floats(0.0, 3e-3))
def test_the_zone_and_the_far_field_fill_the_plate(shape, spacings, elements, margin):
    """Whatever the footprint: the FEM's elements (the hole left out) and the particles' cells
    together are the quarter plate's volume, and the tied particles are exactly those on the
    hole's faces (every one hosted on an element face)."""
    from coupling.study.assemble import _fem_plate
    from coupling.study.selectors import footprint
    from coupling.params import CaseError
    d = 0.5e-3
    case, p, built = _plate(PLATE, "coupled", **{"zone.half_width": spacings * d, "mesh.elements_width": elements,
                                                 "zone.margin": margin})
    p = dict(p, **{"zone.shape": shape})
    try:
        fp = footprint(case.scene, p, built)
    except CaseError:
        return  # (refused: past 0.8 of the half side, or the rod's face off the zone)
    region = _fem_plate(p, built, fp, hole=True)
    cells = fp.cells(d)
    n = int(round(fp.w / d)) + 1
    H = built.lam.thickness
    full = ply_block.build((0.0, 0.0, 0.0), (n, n), [int(round(H / d))], [0.0], d, PLY)
    carved, _ = ply_block.carve(full, cells)
    fem_volume = sum(np.ptp(region.X[e], axis=0).prod() for e in region.mesh.t.T)
    quarter = 0.25 * p["geometry.span"] * p["geometry.width"] * H
    assert fem_volume + carved.volume.sum() == pytest.approx(quarter, rel=1e-10)


@settings(max_examples=4, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(radius=st.floats(0.5e-3, 4e-3), elements=st.sampled_from([2, 3, 5, 8]), coupled=st.booleans())
def test_the_punch_presses_with_its_whole_face_on_the_plate(radius, elements, coupled):
    """A rod's face on the plate's top nodes: the shares sum to the quarter face pi r^2 / 4,
    whatever the element size under it, and only nodes within an element of the face hold one."""
    from coupling.study.assemble import _fem_plate
    from coupling.study.disc import face_shares
    from coupling.study.selectors import Footprint
    case, p, built = _plate(PLATE, "fem", **{"mesh.elements_width": elements})
    fp = Footprint(5e-3, elements, np.inf)
    region = _fem_plate(p, built, fp, hole=False)
    share = face_shares(region, built.lam.thickness, radius)
    assert share.sum() == pytest.approx(np.pi * radius**2 / 4, rel=2e-3)
    on = np.flatnonzero(share > 0)
    assert np.all(np.hypot(*region.X[on, :2].T) < radius + np.sqrt(2) * 5e-3 / elements)


@pytest.mark.parametrize("mode, dem", [pytest.param("fem", None, marks=pytest.mark.slow), ("coupled", "liggghts"),
                                       *[pytest.param("coupled", e, marks=pytest.mark.slow)
                                         for e in ENGINES if e != "liggghts"],
                                       *[pytest.param("dem", e, marks=pytest.mark.slow)  # (YADE: 386 s)
                                         for e in ENGINES if e != "yade"]])
def test_a_plate_under_a_flat_punch_with_its_zone_selected_around_it(femdem, mode, dem):
    """tests/studies/punched_plate.toml, a study written only as a case file: a rod's flat face
    (a 3D flat punch) on the clamped plate, the zone a cylinder about it (zone.shape =
    "impactor"); every mode against the plate's spring-mass closed form, the ledger closed."""
    code, s, err = femdem("run", str(PUNCH), "--mode", mode, *(["--dem", dem] if dem else []),
                          "--set", "clock.t_end=0.17e-3")  # (past the peak, at 0.12-0.13 ms)
    assert code == 0, err
    assert_checks(s)


@pytest.mark.slow  # (14 s; the default suite carves through punched_plate)
def test_the_cylinder_zone_equals_the_box_zone(femdem, tmp_path):
    """The clamped plate's zone as a cylinder of the box's half width: the same plate, so the
    same peak deflection within 1 % (the particles the cylinder leaves to the FEM are far from
    the sphere), each run's checks passing, and fewer particles."""
    text = PLATE.read_text().replace("[zone]\n", '[zone]\nshape = "cylinder"\n')
    path = tmp_path / "cylinder_plate.toml"
    path.write_text(text)
    runs = {}
    for name, case in (("box", PLATE), ("cylinder", path)):
        code, s, err = femdem("run", str(case), "--mode", "coupled")
        assert code == 0, err
        assert_checks(s)
        runs[name] = s["qoi"]
    assert runs["cylinder"]["peak_deflection"] == pytest.approx(runs["box"]["peak_deflection"], rel=0.01)
    assert runs["cylinder"]["model_size"] < runs["box"]["model_size"]


@pytest.mark.parametrize("edit, words", [
    (("[zone]\n", '[zone]\nshape = "cylinder"\n'), None),  # on the bend (a beam): refused
    (("radius = 2e-3", "radius = 4e-3"), ["impactors.punch.radius", "zone"]),
    (('[zone]\nshape = "impactor"', '[zone]\nshape = "cylinder"'), ["zone.half_width", "required"]),
])
def test_a_selector_that_cannot_hold_is_refused_in_one_line(femdem, tmp_path, edit, words):
    """A cylinder zone on a beam, a punch wider than its zone (a 0.5 mm margin), a cylinder
    without its radius: exit 2, one line naming the key, nothing written."""
    if words is None:
        text = (ROOT / "tests" / "studies" / "three_point_bend.toml").read_text().replace(*edit)
        words = ["zone.shape", "cylinder", "box"]
    else:
        text = PUNCH.read_text().replace(*edit)
        if edit[0] == "radius = 2e-3":
            text = text.replace('[zone]\n', '[zone]\nmargin = 0.5e-3\n')
    path = tmp_path / "bad.toml"
    path.write_text(text)
    code, s, err = femdem("run", str(path), "--mode", "coupled")
    assert code == 2, err
    line = err.strip()
    assert "\n" not in line and all(w in line for w in words), line
    assert not (tmp_path / "run0").exists()


@pytest.mark.parametrize("aspect, alpha", [(1.0, 0.00560), (1.4, 0.00691), (2.0, 0.00722)])
def test_the_clamped_plate_point_stiffness_is_timoshenkos(aspect, alpha):
    """The bracket's bending stiffness (Ritz, 10 x 10 clamped polynomials) against Timoshenko &
    Woinowsky-Krieger's clamped isotropic rectangle under a central load, w = alpha P a^2 / D
    (Theory of Plates and Shells, 1959, table 57): a Ritz solution is stiff, so its deflection
    lies below the table's (to its three digits) and within 1.5 % of it (1.2 % at b = 2 a, where
    the long side's ten terms converge slowest)."""
    from coupling.study.closed_forms import clamped_point_stiffness
    E, nu, t, a = 70e9, 0.3, 1e-3, 0.1
    Dv = E * t**3 / (12 * (1 - nu**2))
    D = Dv * np.array([[1, nu, 0], [nu, 1, 0], [0, 0, (1 - nu) / 2]])
    k = clamped_point_stiffness(D, a, aspect * a)
    assert 0.985 * alpha * a**2 / Dv < 1 / k < 1.001 * alpha * a**2 / Dv
