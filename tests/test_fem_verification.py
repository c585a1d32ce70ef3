"""FEM far-field verification cases: closed forms computed from each run's own parameters."""
import numpy as np
import pytest

from conftest import assert_checks


def test_bar_wave_speed(femdem):
    code, s, _ = femdem("run", "bar_wave")
    assert code == 0
    assert_checks(s)
    assert s["checks"]["wave_speed"]["reference"] == pytest.approx(np.sqrt(200e9 / 7800))


def test_bar_wave_follows_set_parameters(femdem):
    # aluminium instead of steel: the reference moves with the parameters, the check still holds
    code, s, _ = femdem("run", "bar_wave", "--set", "material.E=70e9", "--set", "material.rho=2700",
                        "--set", "mesh.element=tri3")
    assert code == 0
    assert_checks(s)
    assert s["checks"]["wave_speed"]["reference"] == pytest.approx(np.sqrt(70e9 / 2700))
    assert s["parameters"]["mesh.element"] == "tri3"


@pytest.mark.parametrize("sets", [[], ["material.G13=3e9", "geometry.length=0.06"]])
def test_cantilever_timoshenko(femdem, sets):
    code, s, _ = femdem("run", "cantilever", *sum((["--set", x] for x in sets), []))
    assert code == 0
    assert_checks(s)


def test_free_vibration_energy_drift(femdem):
    code, s, _ = femdem("run", "free_vibration")
    assert code == 0
    assert_checks(s)
    assert s["clock"]["steps"] == 10000


@pytest.mark.parametrize("sets", [[], ["material.E=70e9", "material.rho=2700", "geometry.length=0.3"]])
def test_column_buckling_euler(femdem, sets):
    code, s, _ = femdem("run", "column_buckling", *sum((["--set", x] for x in sets), []))
    assert code == 0
    assert_checks(s)
    # the column really buckled: lateral deflection far beyond the imperfection
    assert s["qoi"]["max_mid_deflection"] > 20 * s["parameters"]["geometry.imperfection"] * s["parameters"]["geometry.thickness"]
