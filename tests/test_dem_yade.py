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
    code, s, _ = femdem("run", "chung_ooi_1", *_sets(material))
    assert code == 0
    assert_checks(s)
    assert set(s["checks"]) == {"peak_force", "contact_duration", "max_overlap"}


@pytest.mark.parametrize("material", [AL, MG], ids=["al_alloy", "mg_alloy"])
def test_chung_ooi_2_sphere_on_plane(femdem, material):
    code, s, _ = femdem("run", "chung_ooi_2", *_sets(material))
    assert code == 0
    assert_checks(s)
    # the check's reference uses the stand-in sphere; the ideal plane (R* = R, E* = E/(1-nu^2))
    # must agree within about 1 / radius_ratio
    p = s["parameters"]
    E, nu, rho, R, v = (p[k] for k in ("material.E", "material.poisson", "material.rho", "particle.radius",
                                       "impact.velocity"))
    Es, m = E / (1 - nu**2), rho * 4 / 3 * np.pi * R**3
    d = (15 * m * v**2 / (16 * Es * np.sqrt(R))) ** 0.4
    assert s["qoi"]["peak_force"] == pytest.approx(4 / 3 * Es * np.sqrt(R) * d**1.5, rel=2e-3)


@pytest.mark.parametrize("material", [AL_OXIDE, CAST_IRON], ids=["al_oxide", "cast_iron"])
@pytest.mark.parametrize("e", [0.1, 0.3, 0.5, 0.7, 0.9, 1.0])
def test_chung_ooi_3_restitution(femdem, material, e):
    code, s, _ = femdem("run", "chung_ooi_3", *_sets(material), "--set", f"impact.restitution={e}")
    assert code == 0
    assert_checks(s)
    assert s["energy"]["balance_error_rel"] < 0.01  # damping dissipation is booked, not lost


@pytest.mark.parametrize("kind", ["square", "hexagonal"])
def test_bonded_block_modulus_calibration(femdem, kind, tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    code, s, _ = femdem("run", "bonded_block_modulus", "--set", f"packing.kind={kind}")
    assert code == 0
    assert_checks(s)
    assert s["qoi"]["poisson"] == pytest.approx(1 / 3, abs=0.03)  # both lattices are isotropic, nu = 1/3
    # the cache is used the second time and gives the same calibration
    code, s2, _ = femdem("run", "bonded_block_modulus", "--set", f"packing.kind={kind}")
    assert s2["qoi"]["uncalibrated_modulus"] == s["qoi"]["uncalibrated_modulus"]
    assert list((tmp_path / "cache" / "femdem" / "calibration").glob("*.json"))


def test_bond_strength(femdem, tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    code, s, _ = femdem("run", "bond_strength")
    assert code == 0
    assert_checks(s)


def test_bonded_beam_bending(femdem, tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    code, s, _ = femdem("run", "bonded_beam_bending")
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
