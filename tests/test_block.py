"""A block (issue #23): a study of one isotropic material written only as a case file
(tests/studies/punched_block.toml), an alumina block on a floor under a flat punch, its zone
selected around the punch; every mode against Boussinesq's rigid punch on a half-space."""
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conftest import assert_checks

ROOT = Path(__file__).resolve().parents[1]
BLOCK = ROOT / "tests" / "studies" / "punched_block.toml"
GMSH = ROOT / "tests" / "studies" / "gmsh_block.toml"
PRESSED = ROOT / "tests" / "studies" / "pressed_block.toml"
PRESSED_PLATE = ROOT / "tests" / "studies" / "pressed_plate.toml"
ENGINES = ["liggghts", "lammps", "yade"]


@pytest.mark.parametrize("mode, dem, floor", [
    pytest.param("coupled", "liggghts", "fixed", marks=pytest.mark.slow),  # (24 s; the suite: the Gmsh block)
    *[pytest.param("coupled", e, "fixed", marks=pytest.mark.slow) for e in ("lammps", "yade")],
    pytest.param("fem", None, "fixed", marks=pytest.mark.slow),
    pytest.param("fem", None, "sliding", marks=pytest.mark.slow),
    pytest.param("coupled", "liggghts", "sliding", marks=pytest.mark.slow),
    *[pytest.param("dem", e, "fixed", marks=pytest.mark.slow) for e in ("liggghts", "lammps")]])
def test_a_block_under_a_flat_punch_holds_boussinesq(femdem, mode, dem, floor):
    """The punch's peak indentation against the quasi-static rigid punch on a half-space
    (block_spring_mass, 15 %; measured: all-FEM +6 %, coupled and all-DEM +12 %: the lattice has
    three particles across the punch's radius), the ledger closed, on a fixed or a sliding
    floor (the block is ten punch radii deep: the floor barely matters). The coupled run's
    fixed floor under the zone holds a second fully prescribed particle set beside the tie."""
    code, s, err = femdem("run", str(BLOCK), "--mode", mode, *(["--dem", dem] if dem else []),
                          "--set", f"supports.floor.condition={floor}")
    assert code == 0, err
    assert_checks(s)


@pytest.mark.parametrize("mode, dem", [("fem", None),  # (the suite's budget: coupled with -m slow)
                                       *[pytest.param("coupled", e, marks=pytest.mark.slow) for e in ENGINES]])
def test_a_block_meshed_by_gmsh_holds_boussinesq(femdem, mode, dem):
    """tests/studies/gmsh_block.toml: the punched block's FEM from a Gmsh file (its physical
    volume "alumina" the body, its surface "floor" the support; elements graded to the sides and
    the floor, 1 mm cells under the zone): the same check (measured: all-FEM +6 %, coupled
    +12 %), the ledger closed."""
    code, s, err = femdem("run", str(GMSH), "--mode", mode, *(["--dem", dem] if dem else []),
                          "--set", "clock.t_end=16e-6")  # (past the peak, at 11 us)
    assert code == 0, err
    assert_checks(s)


def test_a_gmsh_block_whose_elements_are_not_the_zones_cells_is_refused(femdem):
    """A zone reaching past the file's 1 mm elements (a 5 mm margin: 8 mm, the file's fine square
    ends at 7 mm): exit 2, one line naming the file and what it needs."""
    code, s, err = femdem("run", str(GMSH), "--mode", "coupled", "--set", "zone.margin=5e-3")
    assert code == 2, err
    line = err.strip()
    assert "\n" not in line and all(w in line for w in ("mesh.file", "particle grid")), line


def test_the_block_conserves_mass_in_every_mode():
    """The quarter block's mass: all-FEM, all-DEM (half cells on the symmetry planes and the free
    sides), and coupled (the FEM around the zone plus the carved column's particles) each
    rho x span x width x depth / 4, to round-off (the Gmsh block: its FEM is the cheaper)."""
    from coupling.case import load_case
    case = load_case(str(GMSH))
    p = case.parameters
    quarter = p["materials.alumina.rho"] * p["geometry.span"] * p["geometry.width"] * p["geometry.depth"] / 4
    masses = {}
    for mode in ("fem", "dem", "coupled"):
        sim, built = case.scene.assemble(p, mode, "liggghts")
        m = 0.0
        if built.dyn is not None:
            X, t = built.dyn.region.X, built.dyn.region.mesh.t  # (hexahedra along the axes: their boxes)
            m += float(np.ptp(X[t], axis=0).prod(axis=-1).sum()) * p["materials.alumina.rho"]
        if built.lattice is not None:
            m += float(np.sum(built.lattice.volume)) * p["materials.alumina.rho"]
            built.backend.finalize()
        masses[mode] = m
    assert masses == pytest.approx({"fem": quarter, "dem": quarter, "coupled": quarter}, rel=1e-10)


@pytest.mark.parametrize("edit, words", [
    (('kind = "isotropic"', 'kind = "ply"'), ["materials.alumina."]),
    (("depth = 30e-3", "depth = 30.5e-3"), ["zone.particle_size", "whole number"]),
    (('shape = "rod"', 'shape = "sphere"\nmass = 0.1'), ["block_spring_mass", "rod"]),
    (('at = "bottom"', 'at = "edges"'), ["supports.floor."]),
    (("elements_width = 7", "elements_width = 7\nfile = \"gmsh_block.msh\""), ["no effect with mesh.file"]),
])
def test_a_block_that_cannot_be_built_is_refused_in_one_line(femdem, tmp_path, edit, words):
    """A ply material as the body, a depth that is no whole number of particle rows, the punch
    closed form with a sphere, a plate's support: exit 2, one line, nothing written."""
    text = BLOCK.read_text().replace(*edit)
    if edit[1].startswith('shape = "sphere"'):
        text = text.replace("length = 0.45  # 0.1 kg of steel\nrho = 7850.0\n", "").replace(
            "penalty = 3.7e14  # Pa/m: about E / d\n", "")
    path = tmp_path / "bad.toml"
    path.write_text(text)
    code, s, err = femdem("run", str(path), "--mode", "fem")
    assert code == 2, err
    line = err.strip()
    assert "\n" not in line and all(w in line for w in words), line
    assert not (tmp_path / "run0").exists()


@pytest.mark.parametrize("mode, dem", [*[pytest.param(m, e, marks=pytest.mark.slow)  # (the suite: the load's
                                         for m, e in [("fem", None), ("coupled", "liggghts"), ("dem", "liggghts"),
                                                      ("coupled", "lammps"), ("coupled", "yade")]]])
# shares, test_the_pressure_disc_is_applied_whole_in_every_mode; a coupled block, the Gmsh one)
def test_a_block_under_a_pressure_history_holds_boussinesq(femdem, mode, dem):
    """tests/studies/pressed_block.toml: a load by selector with a table for its history (a
    pressure disc on the top face, a slow ramp): the disc's centre against the half-space's
    quasi-static 2 (1 - nu^2) F / (pi a E) (measured: all-FEM -1.7 %, coupled and all-DEM
    -6.4 %), the ledger closed (the load's work booked)."""
    code, s, err = femdem("run", str(PRESSED), "--mode", mode, *(["--dem", dem] if dem else []))
    assert code == 0, err
    assert_checks(s)
    assert s["qoi"]["peak_load"] == pytest.approx(1.4e3, rel=1e-12)


@pytest.mark.parametrize("study, mode, zone", [(PRESSED, "dem", None), (PRESSED, "coupled", 2.5e-3),
                                               (PRESSED_PLATE, "coupled", 1.5e-3)])
def test_the_pressure_disc_is_applied_whole_in_every_mode(study, mode, zone):
    """The FEM faces' and the top particles' shares of the disc sum to the quarter model's
    quarter of the load however the zone splits it (the block's 3 mm disc on a zone selected
    around it, and on a cylinder zone of 2.5 mm, the rest on the FEM's faces around it; the
    plate's 2 mm disc on a 1.5 mm cylinder), to the midpoint sums' resolution."""
    from coupling.case import load_case
    case = load_case(str(study))
    p = case.parameters
    if zone:
        p = dict(p, **{"zone.shape": "cylinder", "zone.half_width": zone})
    sim, built = case.scene.assemble(p, mode, "liggghts")
    on_fem = sum(float(np.sum(L.amplitude)) for L in (built.dyn.loads if built.dyn is not None else []))
    on_particles = sum(float(L.share[:, 2].sum()) for L in built.particle_loads)
    if built.backend is not None:
        built.backend.finalize()
    assert on_fem + on_particles == pytest.approx(-0.25, rel=2e-3)
    if zone:
        assert on_fem < -0.02 and on_particles < -0.02  # split between both


@pytest.mark.parametrize("mode, dem", [pytest.param("fem", None, marks=pytest.mark.slow),
                                       *[pytest.param("coupled", e, marks=pytest.mark.slow) for e in ENGINES]])
def test_a_plate_under_a_pressure_history_holds_its_static_bracket(femdem, mode, dem):
    """tests/studies/pressed_plate.toml: the clamped plate under a smooth pressure ramp on a
    central disc against the quasi-static bracket (point-load bending, alone and with Mindlin's
    shear about the disc; measured: all-FEM +7 %, coupled +10 % above its shear side, which the
    15 % covers), the ledger closed."""
    code, s, err = femdem("run", str(PRESSED_PLATE), "--mode", mode, *(["--dem", dem] if dem else []))
    assert code == 0, err
    assert_checks(s)


@pytest.mark.slow
@settings(max_examples=4, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(E=st.floats(30e9, 400e9), nu=st.floats(0.15, 0.3), velocity=st.floats(0.05, 0.2), length=st.floats(0.2, 0.9),
       coupled=st.booleans())
def test_the_punched_block_holds_boussinesq_for_other_materials_and_impacts(femdem, E, nu, velocity, length,
                                                                             coupled):
    """The Gmsh block under its punch with another modulus, Poisson ratio, speed and punch mass
    (the penalty about E / d, as in the file): the check against Boussinesq holds (15 %), the
    ledger closed; the contact lasts pi sqrt(M / k), so the run is cut to past the peak."""
    k = 2 * E * 3e-3 / (1 - nu**2)
    mass = 7850.0 * np.pi * 3e-3**2 * length
    t_peak = 0.5 * np.pi * np.sqrt(mass / k)
    code, s, err = femdem("run", str(GMSH), "--mode", "coupled" if coupled else "fem",
                          f"--set=materials.alumina.E={E}", f"--set=materials.alumina.nu={nu}",
                          f"--set=impactors.punch.velocity={velocity}", f"--set=impactors.punch.length={length}",
                          f"--set=impactors.punch.penalty={E / 1e-3}", f"--set=clock.t_end={1.5 * t_peak}")
    assert code == 0, err
    assert_checks(s)
