"""Bad input: one clear line naming key, value and what is allowed; exit code 2; nothing written."""
import pytest
from hypothesis import given, strategies as st

from coupling.params import CaseError, Param, resolve


def _bad_case(tmp_path, body):
    p = tmp_path / "bad.toml"
    p.write_text('[case]\nscene = "bar_wave"\n' + body)
    return str(p)


@pytest.mark.parametrize("body, words", [
    ("[material]\nrho = -7800.0\n", ["material.rho", "-7800", "> 0"]),
    ("[material]\nyoung = 1e9\n", ["material.young", "unknown key"]),
    ("[mesh]\nelement = 'hex27'\n", ["mesh.element", "hex27", "quad4"]),
    ("[mesh]\nelements_along = 2.5\n", ["mesh.elements_along", "integer"]),
    ("[clock]\ndt = 1.0\n", ["clock.dt", "stable step"]),
])
def test_bad_case_file(femdem, tmp_path, body, words):
    code, summary, err = femdem("run", _bad_case(tmp_path, body))
    assert code == 2 and summary is None
    line = err.strip()
    assert len(line.splitlines()) == 1, line
    for w in words:
        assert w in line, (w, line)
    assert not list(tmp_path.glob("run*")), "nothing may be left behind on bad input"


@pytest.mark.parametrize("args, words", [
    (["--dem", "fluent"], ["--dem fluent", "yade, liggghts, lammps"]),
    (["--set", "material.E=soft"], ["material.E", "soft", "number"]),
    (["--set", "material.E"], ["key=value"]),
    (["--mode", "coupled"], ["--mode coupled", "fem"]),
])
def test_bad_command_line(femdem, args, words):
    code, summary, err = femdem("run", "bar_wave", *args)
    assert code == 2 and summary is None
    assert len(err.strip().splitlines()) == 1
    for w in words:
        assert w in err, (w, err)


def test_unknown_case_and_scene(femdem, tmp_path):
    code, _, err = femdem("run", "no_such_case")
    assert code == 2 and "bundled" in err
    p = tmp_path / "s.toml"
    p.write_text('[case]\nscene = "warp_drive"\n')
    code, _, err = femdem("run", str(p))
    assert code == 2 and "case.scene" in err and "bar_wave" in err


def test_resolved_parameters_round_trip(femdem):
    """Every echoed parameter is accepted back by --set and gives the same resolved set."""
    code, s, _ = femdem("run", "bar_wave", "--set", "mesh.elements_along=60", "--set", "clock.safety=0.8")
    assert code == 0
    sets = sum((["--set", f"{k}={str(v).lower() if isinstance(v, bool) else v}"] for k, v in s["parameters"].items()), [])
    code, s2, _ = femdem("run", "bar_wave", *sets)
    assert code == 0 and s2["parameters"] == s["parameters"]


@given(st.floats(allow_nan=True, allow_infinity=True))
def test_positive_param_accepts_exactly_positive_finite(x):
    p = Param(1.0, kind="float", low=0.0, open_low=True)
    ok = x == x and abs(x) != float("inf") and x > 0
    try:
        assert p.coerce("k", x) == x and ok
    except CaseError as exc:
        assert not ok and "k = " in str(exc)


@given(st.dictionaries(st.sampled_from(["a.x", "a.y", "b.z", "c.w"]), st.integers(-5, 5)))
def test_resolve_rejects_unknown_and_out_of_range(given_values):
    schema = {"a.x": Param(0, kind="int", low=0), "a.y": Param(0, kind="int"), "b.z": Param(1, kind="int", low=1, high=3)}
    bad = "c.w" in given_values or given_values.get("a.x", 0) < 0 or not 1 <= given_values.get("b.z", 1) <= 3
    try:
        out = resolve(schema, given_values, "test")
        assert not bad and set(out) == set(schema)
    except CaseError:
        assert bad


@pytest.mark.parametrize("setting, words", [
    ("material.rho=7.8", ["material.rho", "implausible", "kg/m^3"]),      # g/cm^3 by mistake
    ("material.E=200000", ["material.E", "implausible", "Pa"]),          # MPa by mistake
])
def test_unit_slips_are_caught(femdem, setting, words):
    code, s, err = femdem("run", "bar_wave", "--set", setting)
    assert code == 2 and s is None
    for w in words:
        assert w in err


@pytest.mark.parametrize("case, args, words", [
    ("cfrp_beam_impact_coarse", ["--set=load.file=/nonexistent/drop.csv"], ["load.file", "/nonexistent/drop.csv"]),
    ("cfrp_beam_impact_coarse", ["--set=dem.particle_size=5e-3"], ["dem.particle_size", "whole number"]),
    ("cfrp_beam_impact_coarse", ["--set=geometry.span=0.9"], ["geometry.span", "0.9", "allowed"]),
    ("cfrp_beam_impact_coarse", ["--set=dem.half_width=0.5"], ["dem.half_width", "allowed"]),
    ("rod_impact_coarse", ["--set=interface.penalty=2e10"], ["interface.penalty", "toughness"]),
    ("rod_impact_coarse", ["--set=fem.integration=selective"], ["fem.integration", "allowed"]),
    ("rod_impact_coarse", ["--mode", "dem"], ["--mode dem", "fem, coupled"]),
    ("rod_impact_coarse", ["--mode", "coupled", "--set=dem.particle_size=0.005"], ["dem.particle_size", "divide"]),
    ("panel_buckling_coarse", ["--mode", "coupled", "--set=dem.window_ahead=0.03"], ["dem.window_ahead", "allowed"]),
    ("panel_buckling_coarse", ["--mode", "coupled", "--set=particle.radius=2e-4"], ["particle.radius", "allowed"]),
])
def test_bad_input_of_the_seed_scenes(femdem, case, args, words):
    code, summary, err = femdem("run", case, *args)
    assert code == 2 and summary is None, err
    assert len(err.strip().splitlines()) == 1, err
    for w in words:
        assert w in err, (w, err)
