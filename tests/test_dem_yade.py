"""DEM back-end verification (YADE): Chung & Ooi benchmarks against Hertz theory."""
import numpy as np
import pytest

from conftest import assert_checks

GLASS = ["material.E=48e9", "material.poisson=0.20", "material.rho=2800"]
LIMESTONE = ["material.E=20e9", "material.poisson=0.25", "material.rho=2500"]
AL = ["material.E=70e9", "material.poisson=0.30", "material.rho=2699"]
MG = ["material.E=40e9", "material.poisson=0.35", "material.rho=1800"]
AL_OXIDE = ["material.E=380e9", "material.poisson=0.23", "material.rho=4000"]
CAST_IRON = ["material.E=100e9", "material.poisson=0.25", "material.rho=7000"]


def _sets(items):
    return sum((["--set", x] for x in items), [])


@pytest.mark.parametrize("material", [GLASS, LIMESTONE], ids=["glass", "limestone"])
def test_chung_ooi_1_two_spheres(femdem, material):
    code, s, _ = femdem("run", "chung_ooi_1", "--dem", "yade", *_sets(material))
    assert code == 0
    assert_checks(s)
    assert set(s["checks"]) == {"peak_force", "contact_duration", "max_overlap"}


@pytest.mark.parametrize("material", [AL, MG], ids=["al_alloy", "mg_alloy"])
def test_chung_ooi_2_sphere_on_plane(femdem, material):
    code, s, _ = femdem("run", "chung_ooi_2", "--dem", "yade", *_sets(material))
    assert code == 0
    assert_checks(s)
    # the check's reference uses the stand-in sphere; the ideal plane (R* = R, E* = E/(1-nu^2))
    # must agree within about 1 / radius_ratio
    p = s["parameters"]
    E, nu, rho, R, v = (p[k] for k in ("material.E", "material.poisson", "material.rho", "sphere.radius",
                                       "impact.velocity"))
    Es, m = E / (1 - nu**2), rho * 4 / 3 * np.pi * R**3
    d = (15 * m * v**2 / (16 * Es * np.sqrt(R))) ** 0.4
    assert s["qoi"]["peak_force"] == pytest.approx(4 / 3 * Es * np.sqrt(R) * d**1.5, rel=2e-3)


@pytest.mark.parametrize("material", [AL_OXIDE, CAST_IRON], ids=["al_oxide", "cast_iron"])
@pytest.mark.parametrize("e", [0.1, 0.3, 0.5, 0.7, 0.9, 1.0])
def test_chung_ooi_3_restitution(femdem, material, e):
    code, s, _ = femdem("run", "chung_ooi_3", "--dem", "yade", *_sets(material), "--set", f"impact.restitution={e}")
    assert code == 0
    assert_checks(s)
    assert s["energy"]["balance_error_rel"] < 0.01  # damping dissipation is booked, not lost


# the square lattice with -m slow (15 s, the suite's ten minutes, session 44): the suite
# calibrates it on LIGGGHTS and LAMMPS (tests/test_engines.py::test_bonded_block)
@pytest.mark.parametrize("kind", [pytest.param("square", marks=pytest.mark.slow), "hexagonal"])
def test_bonded_block_modulus_calibration(femdem, kind, tmp_path, monkeypatch):
    monkeypatch.setenv("FEMDEM_CACHE_DIR", str(tmp_path / "cache" / "femdem"))
    code, s, _ = femdem("run", "bonded_block_modulus", "--dem", "yade", "--set", f"packing.kind={kind}")
    assert code == 0
    assert_checks(s)
    assert s["qoi"]["poisson"] == pytest.approx(1 / 3, abs=0.03)  # both lattices are isotropic, nu = 1/3
    # the cache is used the second time and gives the same calibration
    code, s2, _ = femdem("run", "bonded_block_modulus", "--dem", "yade", "--set", f"packing.kind={kind}")
    assert s2["qoi"]["uncalibrated_modulus"] == s["qoi"]["uncalibrated_modulus"]
    assert list((tmp_path / "cache" / "femdem" / "calibration").glob("*.json"))


def test_bond_strength(femdem, tmp_path, monkeypatch):
    monkeypatch.setenv("FEMDEM_CACHE_DIR", str(tmp_path / "cache" / "femdem"))
    code, s, _ = femdem("run", "bond_strength", "--dem", "yade")
    assert code == 0
    assert_checks(s)


@pytest.mark.slow  # suite budget: YADE's law path runs in tests/test_study.py's coupled-yade runs
def test_bonded_beam_bending(femdem, tmp_path, monkeypatch):
    monkeypatch.setenv("FEMDEM_CACHE_DIR", str(tmp_path / "cache" / "femdem"))
    code, s, _ = femdem("run", "bonded_beam_bending", "--dem", "yade")
    assert code == 0
    assert_checks(s)


@pytest.mark.parametrize("process", ["in-process", "worker"])
def test_engine_checkpoint_restore_is_bit_identical(tmp_path, process):
    from dem_region import packing
    from dem_region.backends import make_backend
    from dem_region.scene import DemScene
    r = 0.0005
    x = packing.square_2d((0, 0), (20 * 2 * r, 5 * 2 * r), r)
    bonds, fam = packing.square_bonds(x, r)
    v = np.random.default_rng(0).normal(size=(len(x), 3)) * [0.1, 0.1, 0]
    scene = DemScene(x, r, 2000.0, bonds, kn=np.where(fam, 1e6, 2e6), ks=0.0, plane=True, velocity=v)
    eng = make_backend("yade", process)
    try:
        eng.build(scene)
        eng.set_dt(0.5 * eng.critical_dt())
        eng.start(None)
        for _ in range(50):
            eng.advance(None)
        eng.checkpoint(tmp_path / "ck.yade.bz2")
        for _ in range(50):
            eng.advance(None)
        straight = eng.positions()
        eng.restore(tmp_path / "ck.yade.bz2")
        for _ in range(50):
            eng.advance(None)
        assert np.array_equal(eng.positions(), straight)
        assert not np.array_equal(straight, x)
    finally:
        eng.finalize()


def test_broken_bonds_are_listed_where_the_block_fails():
    """A bonded chain pulled at both ends with one weak bond breaks there, and only there."""
    from dem_region.backends import make_backend
    from dem_region.scene import DemScene
    r, n = 0.001, 12
    x = np.column_stack([2 * r * np.arange(n), np.zeros(n), np.zeros(n)])
    bonds = np.column_stack([np.arange(n - 1), np.arange(1, n)])
    strength = np.full(n - 1, np.inf)
    strength[5] = 1.0  # N
    eng = make_backend("yade")
    try:
        eng.build(DemScene(x, r, 2000.0, bonds, kn=1e6, ks=0.0, bond_strength=strength, plane=True))
        ends = np.array([0, n - 1])
        eng.prescribe(ends)
        eng.set_dt(0.2 * eng.critical_dt())
        pull = lambda: eng.set_velocities(ends, np.array([[-0.05, 0, 0], [0.05, 0, 0]]))
        eng.start(pull)
        assert eng.bond_state()["broken"] == 0
        for _ in range(3000):
            eng.advance(pull)
        s = eng.bond_state()
        assert s["broken"] == 1 and s["intact"] == n - 2
        i, j, t, bx, *_ = s["broken_list"][0]
        assert (i, j) == (5, 6) and t > 0 and abs(bx - 11 * r) < 2 * r
    finally:
        eng.finalize()


def test_virtual_shear_of_an_isotropic_lattice(tmp_path, monkeypatch):
    """The calibrated square layer is isotropic: G = E / (2 (1 + nu)) with nu = 1/3."""
    from dem_region import calibration
    from coupling.scenes.bonded_block import layer
    from coupling.case import load_case
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    p = dict(load_case("bonded_block_modulus").parameters, **{"geometry.columns": 20, "geometry.rows": 20})
    scene, unit, _ = calibration.calibrate_modulus(layer(p), p["material.E"])
    G = calibration.virtual_shear(scene)
    assert G == pytest.approx(p["material.E"] / (2 * (1 + unit.nu)), rel=0.05)


@pytest.mark.slow  # suite budget: the ply lattices take their moduli in closed form (ply_lattice)
def test_orthotropic_ply_calibration(tmp_path, monkeypatch):
    """A ply layer calibrated to E11 / E22 of the seed paper's graphite/epoxy (Table 1)."""
    from dem_region import calibration
    from coupling.scenes.bonded_block import layer
    from coupling.case import load_case
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    p = dict(load_case("bonded_block_modulus").parameters, **{"geometry.columns": 24, "geometry.rows": 12})
    E11, E22 = 156e9, 9.09e9
    _, (e1, e2) = calibration.calibrate_orthotropic(layer(p), E11, E22)
    assert e1 == pytest.approx(E11, rel=0.05) and e2 == pytest.approx(E22, rel=0.05)


def test_ply_aware_layers_and_filled_elements():
    from dem_region import packing
    from fem_region import mesh
    r = 0.0005
    x, ply, bonds, fam = packing.laminate_layers(4 * r * 2, 3, 20 * 2 * r, r)
    assert np.bincount(ply).tolist() == [4 * 21] * 3  # 4 rows of 21 per ply
    inter = bonds[fam == 2]
    assert (ply[inter[:, 0]] != ply[inter[:, 1]]).all()
    assert len(inter) == 2 * (21 + 2 * 20)  # per interface: 21 axial + 2 x 20 diagonal
    with pytest.raises(ValueError):
        packing.laminate_layers(3.5 * r, 2, 0.01, r)
    m = mesh.rectangle(np.linspace(0, 0.02, 5), np.linspace(0, 0.01, 3))
    xs, rs = packing.fill_elements(m, np.array([1, 2]), 0.0004, attempts=20000)
    fraction = np.sum(np.pi * rs**2) / (2 * 0.005 * 0.005)
    assert 0.3 < fraction < 0.6  # random sequential addition in 2D jams near 0.55
    finder = m.element_finder()
    assert all(finder(np.array([a]), np.array([b]))[0] in (1, 2) for a, b in xs[:, :2])


def test_sphere_on_a_wall(femdem):
    """A rigid wall of the neutral scene: elastic rebound (restitution 1) and Hertz contact.
    YADE's wall geometry hands Mindlin a contact radius of R/2 (not the plane's R), which is
    why chung_ooi_2 stands a large fixed sphere in for the plane; here the closed form with
    R* = R/2 is what the engine must match."""
    from dem_region.backends import make_backend
    from dem_region.scene import DemScene, Wall
    from coupling.scenes.chung_ooi import hertz
    E, nu, rho, R, v = 70e9, 0.3, 2699.0, 0.1, 0.2
    scene = DemScene(np.array([[0, 0, R * (1 + 1e-6)]]), R, rho, np.zeros((0, 2)), 0.0, 0.0, young=E, poisson=nu,
                     contact="hertz_mindlin", velocity=[[0, 0, -v]], walls=[Wall(2, 0.0, 1)])
    ref = hertz({"material.E": E, "material.poisson": nu, "material.rho": rho, "sphere.radius": R,
                 "impact.velocity": v, "plane.radius_ratio": 1.0, "plane.stiffness_ratio": 1e6}, 2)
    eng = make_backend("yade")
    try:
        eng.build(scene)
        eng.set_dt(ref["contact_duration"] / 400)
        eng.start(None)
        F = []
        for _ in range(600):
            eng.advance(None)
            F.append(eng.forces([0])[0, 2])
        assert max(F) == pytest.approx(ref["peak_force"], rel=0.01)
        assert eng.velocities()[0, 2] == pytest.approx(v, rel=1e-3)
        assert eng.positions().shape == (1, 3)
    finally:
        eng.finalize()


def test_a_process_that_used_yade_leaves_no_temporary_directory():
    """YADE makes /tmp/yade-XXXXXX at import; a process of ours (a worker, a run) removes it at
    exit, twice imported or once (one was left by every run and worker before)."""
    import subprocess
    import sys
    from pathlib import Path
    code = ("import os; from dem_region.backends.yade import _import_yade; yade, _ = _import_yade(); _import_yade(); "
            "print(os.path.dirname(yade.O.tmpFilename()))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                       cwd=Path(__file__).resolve().parent.parent)
    made = Path(r.stdout.strip().splitlines()[-1])
    assert r.returncode == 0 and made.name.startswith("yade-") and not made.exists()


@pytest.mark.parametrize("raised", [ValueError("a defect in the hook"), KeyboardInterrupt()])
def test_what_the_hook_raises_reaches_the_caller_as_itself(capfd, raised):
    """An exception in the coupling hook (YADE runs it from a PyRunner) reaches advance's caller
    as itself, after the step, with nothing printed; and the engine steps on afterwards. Through
    the PyRunner it became RuntimeError("PyRunner error") with its traceback on the terminal:
    Ctrl-C and SIGTERM during a YADE run ended as an internal error, not as an interrupted run
    left to resume."""
    from dem_region.backends import make_backend
    from dem_region.scene import DemScene
    r, n = 0.001, 4
    x = np.column_stack([2 * r * np.arange(n), np.zeros(n), np.zeros(n)])
    eng = make_backend("yade")
    try:
        eng.build(DemScene(x, r, 2000.0, np.column_stack([np.arange(n - 1), np.arange(1, n)]), kn=1e6, ks=0.0,
                           plane=True))
        eng.set_dt(0.2 * eng.critical_dt())
        calls = []
        eng.start(lambda: calls.append(1))

        def hook():
            calls.append(1)
            raise raised
        with pytest.raises(type(raised)):
            eng.advance(hook, 5)
        assert len(calls) == 2  # the step that raised was the last
        eng.advance(lambda: calls.append(1), 3)
        assert len(calls) == 5
    finally:
        eng.finalize()
    out, err = capfd.readouterr()
    assert "Traceback" not in out + err and "PyRunner" not in out + err, err
